#pragma once
// Photometric sub-pixel refinement for the extrema tracker: the translation of
// a small patch between two smoothed images (inverse-compositional Gauss-Newton,
// zero-mean residuals so a brightness offset does not bias it; optionally a
// per-patch gain too, so that an exposure step does not bias it either).
#include <Eigen/Core>

#include <opencv2/core.hpp>

namespace vitamin_e::tracking {

struct PatchAlignParams {
  int radius = 2;                // patch is (2r+1)^2 pixels, r in [1, 4]
  int iterations = 2;            // Gauss-Newton steps (>= 1)
  float max_shift = 1.0f;        // fail if the result is farther than this from the start [px]
  bool compensate_gain = false;  // also fit a contrast gain a: cur - mean = a (prev - mean); fails when
                                 // a leaves [1/4, 4] (the patch lost or inverted its contrast)
};

// Finds p such that the patch of `cur` at p matches the patch of `prev` at p0
// (both CV_32FC1, sub-pixel positions, bilinear sampling), starting from *p.
// With compensate_gain, `gain` (optional) receives the fitted contrast gain.
// Returns false (and leaves *p unchanged) when a patch leaves the image, the
// patch has no 2D texture (singular normal matrix) or the step diverges
// beyond max_shift from the start.
bool alignPatch(const cv::Mat& prev, const cv::Mat& cur, const Eigen::Vector2f& p0, const PatchAlignParams& params,
                Eigen::Vector2f* p, float* gain = nullptr);

}  // namespace vitamin_e::tracking
