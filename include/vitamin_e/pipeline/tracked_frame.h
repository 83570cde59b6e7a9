#pragma once
// The hand-over between the two stages of the SLAM system: what the tracking
// stage (dense tracker + undistortion) produces for the mapping stage.
#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <cstdint>
#include <string>
#include <vector>

namespace vitamin_e::pipeline {

// A 2D track in the current frame, undistorted.
struct FrameTrack {
  std::uint64_t id;
  Eigen::Vector2f uv;      // distorted pixel
  Eigen::Vector2d xy;      // normalized undistorted
  std::uint8_t intensity;
  std::int8_t polarity;    // sign of the image curvature at the extremum (+1 / -1)
};

// The output of the tracking stage, the input of the mapping stage.
struct TrackedFrame {
  std::uint64_t frame_index = 0;
  double timestamp = 0.0;
  std::string timestamp_text;
  std::vector<FrameTrack> tracks;
  cv::Mat image;  // the input image (shared, not copied): the relocalizer describes keyframes and lost frames
  double tracking_ms = 0.0;
  bool skipped = false;  // stamp did not increase: nothing tracked
  std::string message;
};

}  // namespace vitamin_e::pipeline
