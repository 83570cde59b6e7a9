#pragma once
// Building blocks of the dense tracker: the curvature image, its local extrema,
// hill climbing of F = s*kappa + lambda*w(|x - x_bar|) and sub-pixel refinement.
// Exposed for tests and for callers that want the curvature image itself.
#include <Eigen/Core>
#include <vector>

#include <opencv2/core.hpp>

namespace vitamin_e::tracking {

// kappa = fy^2 fxx - 2 fx fy fxy + fx^2 fyy of `gray` (CV_8UC1 or CV_32FC1),
// smoothed first by a Gaussian of `sigma` px (0 = none); derivatives are
// central differences of the smoothed image (= separable [-1 0 1]/2 and
// [1 -2 1] filters). Output CV_32FC1 of the same size, 0 on the 1-px border.
// `stripes` > 1 splits the rows over cv::parallel_for_.
void computeCurvature(const cv::Mat& gray, double sigma, cv::Mat* kappa, int stripes = 1, cv::Mat* smoothed = nullptr);

// Robust curvature scale: median |kappa| over a sparse grid (every `step` px),
// ignoring exact zeros; 0 for a flat image.
float robustCurvatureScale(const cv::Mat& kappa, int step = 3);

struct Extremum {
  int x = 0, y = 0;
  float kappa = 0.f;  // signed raw curvature; > 0: maximum of kappa, < 0: maximum of -kappa
};

// Strict local maxima of kappa (kappa > 0) and of -kappa (kappa < 0) over the
// (2r+1)^2 window, with |kappa| >= threshold, at least `border` px from the edge.
// Output in row-major order.
void detectExtrema(const cv::Mat& kappa, int nms_radius, float threshold, int border, std::vector<Extremum>* out,
                   int stripes = 1);

struct ClimbParams {
  float sign = 1.f;    // +1 climbs kappa, -1 climbs -kappa
  float lambda = 0.f;  // prior weight, in the raw units of kappa
  float sigma2 = 9.f;  // Geman-McClure sigma^2 of w [px^2]
  int max_steps = 10;
  int border = 2;  // the climb stays at least this far from the image edge
};

// Hill climbing over 8 neighbours from round(prediction) on
// F(p) = sign*kappa(p) + lambda*(1 - d^2/(d^2 + sigma^2)), d = |p - prediction|.
// Returns false if the start is outside the allowed area or no local maximum
// is reached within max_steps; *out is the last position in any case.
bool hillClimb(const cv::Mat& kappa, const Eigen::Vector2f& prediction, const ClimbParams& params,
               Eigen::Vector2i* out);

// Sub-pixel position of the extremum at integer p: separable parabola fit of
// sign*kappa over the 3x3 neighbourhood; the offset is clamped to +-0.5 px.
// `peak` (optional) receives sign*kappa of the fitted quadratic at that
// position: the height of the peak independent of where it falls between
// pixels (the sample at p under-reads a peak that falls between pixels).
Eigen::Vector2f refineSubpixel(const cv::Mat& kappa, const Eigen::Vector2i& p, float sign, float* peak = nullptr);

// How well the extremum at integer p is localized: the flatter principal
// curvature of sign*kappa (the larger eigenvalue of its 3x3 Hessian, negated)
// over the peak value sign*kappa(p), in 1/px^2. A round, sharp peak scores high;
// a ridge (edge-like), a saddle or a plateau scores <= 0 or near 0, and its
// position slides along the flat direction under noise. 0 at the image border
// or when sign*kappa(p) <= 0.
float peakSharpness(const cv::Mat& kappa, const Eigen::Vector2i& p, float sign);

// Bilinear sample of a CV_32FC1 image (clamped at the border).
float sampleBilinear(const cv::Mat& img, float x, float y);

}  // namespace vitamin_e::tracking
