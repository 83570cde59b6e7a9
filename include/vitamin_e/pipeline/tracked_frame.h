#pragma once
// The hand-over between the two stages of the SLAM system: what the tracking
// stage (dense tracker + undistortion) produces for the mapping stage.
#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <opencv2/core.hpp>
#include <string>
#include <utility>
#include <vector>

namespace vitamin_e::pipeline {

// A 2D track in the current frame, undistorted.
struct FrameTrack {
  std::uint64_t id = 0;
  Eigen::Vector2f uv = Eigen::Vector2f::Zero();  // distorted pixel
  Eigen::Vector2d xy = Eigen::Vector2d::Zero();  // normalized undistorted
  std::uint8_t intensity = 0;
  std::int8_t polarity = 1;  // sign of the image curvature at the extremum (+1 / -1)
  int age = 0;               // frames tracked before this one (0: detected in this frame)
};

// The output of the tracking stage, the input of the mapping stage.
struct TrackedFrame {
  std::uint64_t frame_index = 0;
  std::uint64_t sequence = 0;  // the tracking stage's call count (skipped frames included): tags the mapping's drops
  double timestamp = 0.0;
  std::string timestamp_text;
  std::vector<FrameTrack> tracks;
  cv::Mat image;  // the input image (shared, not copied): the relocalizer describes keyframes and lost frames
  double tracking_ms = 0.0;
  // The tracker's counts (FrameDiagnostics): tracks detected and ended this
  // frame, the ended ones by the check that ended them, and each ended track.
  int tracks_born = 0;
  int tracks_lost = 0;
  int tracks_dropped = 0;     // tracks of the previous frame ended by the back end before this one was tracked
  int tracks_from_prior = 0;  // tracks found from the map's prior after the flow lost them
  std::map<std::string, int> lost_by;
  std::vector<std::pair<std::uint64_t, const char*>> ended;  // id, reason (static string)
  bool skipped = false;                                      // stamp did not increase: nothing tracked
  bool mapper_behind = false;   // PipelinedSystem: the next frame was tracked before the mapper took this one
  bool priors_awaited = false;  // PipelinedSystem: the next frame's tracker waits for this one's priors
  std::string message;
};

}  // namespace vitamin_e::pipeline
