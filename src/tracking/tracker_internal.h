#pragma once
// Internal helpers of DenseTracker (not installed): the shrunk-image features
// for the dominant flow and the noise estimate for the adaptive smoothing.
#include <Eigen/Core>
#include <vector>

#include <opencv2/core.hpp>

#include "vitamin_e/tracking/brief.h"
#include "vitamin_e/tracking/dense_tracker.h"

namespace vitamin_e::tracking {

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
