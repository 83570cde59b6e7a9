#pragma once
// Internal helpers of DenseTracker (not installed): striped parallel loops, the
// shrunk-image features for the dominant flow and the noise estimate for the
// adaptive smoothing.
#include <Eigen/Core>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/core/utility.hpp>

#include "vitamin_e/tracking/brief.h"
#include "vitamin_e/tracking/dense_tracker.h"

namespace vitamin_e::tracking {

// Runs body(begin, end) over [0, n) in `stripes` chunks on cv::parallel_for_;
// serially when stripes <= 1 or n < min_parallel (too little work to share).
template <class F>
void forStripes(int n, int stripes, int min_parallel, const F& body) {
  if (stripes <= 1 || n < min_parallel) {
    body(0, n);
    return;
  }
  cv::parallel_for_(
      cv::Range(0, stripes),
      [&](const cv::Range& r) {
        for (int s = r.start; s < r.end; ++s) {
          body(static_cast<int>(static_cast<long>(n) * s / stripes),
               static_cast<int>(static_cast<long>(n) * (s + 1) / stripes));
        }
      },
      stripes);
}

// Keypoints and descriptors of the shrunk image, positions in full-res pixels.
struct SmallFeatures {
  std::vector<Eigen::Vector2d> pos;
  std::vector<BriefDescriptor> desc;
  std::vector<signed char> sign;
};

// Curvature extrema of `gray` shrunk by cfg.brief_scale (the strongest
// cfg.brief_max_keypoints), described by BRIEF on the smoothed small image.
void extractSmallFeatures(const cv::Mat& gray, const TrackerConfig& cfg, const BriefExtractor& brief,
                          SmallFeatures* out);

// Noise sigma (Immerkaer 1996: mean |I * [1 -2 1; -2 4 -2; 1 -2 1]| * sqrt(pi/2) / 6)
// over the median raw gradient magnitude, on a sparse set of rows.
double noiseToGradientRatio(const cv::Mat& gray, std::vector<float>* scratch);

}  // namespace vitamin_e::tracking
