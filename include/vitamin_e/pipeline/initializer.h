#pragma once
// Monocular initialization: waits for parallax between a reference frame and
// the current one, then builds the first two keyframes and their landmarks from
// the two-view geometry (essential matrix, or a homography on a planar view).
#include <cstdint>
#include <deque>
#include <string>
#include <unordered_map>
#include <vector>

#include <Eigen/Geometry>

#include "vitamin_e/map/map.h"
#include "vitamin_e/pipeline/frame_context.h"
#include "vitamin_e/pipeline/system_config.h"

namespace vitamin_e::pipeline {

// A frame seen while initializing: localized once the map exists.
struct PendingFrame {
  std::uint64_t frame_index = 0;
  double timestamp = 0.0;
  std::string timestamp_text;
  std::unordered_map<std::uint64_t, Eigen::Vector2d> xy;  // normalized observation per track id
};

// The map two views give: the reference frame's keyframe and the current one's,
// the landmarks triangulated between them, and the frames seen in between.
struct InitialMap {
  map::Keyframe reference;
  map::Keyframe current;
  std::vector<map::NewLandmark> landmarks;
  PendingFrame reference_frame;
  std::vector<PendingFrame> between;  // frames strictly between reference and current, oldest first
  double parallax_deg = 0.0;
  bool from_homography = false;  // planar scene: the motion came from the homography (two_view.h)
  bool ambiguous = false;        // another motion explained the views as well (the map may be built on the wrong one)
  std::string notes;             // planar scene / ambiguity remarks for the frame message
};

struct InitAttempt {
  bool initialized = false;
  std::string message;  // why it is still waiting
  InitialMap map;       // when initialized
};

// Where a new map is placed: the reference camera's pose in the world and the
// length of the two-view baseline in map units.
struct MapAnchor {
  Eigen::Isometry3d T_w_ref = Eigen::Isometry3d::Identity();
  double scale = 1.0;
};

class Initializer {
 public:
  Initializer(const SystemConfig& config, double focal_px);

  // Adds the frame and tries to initialize against the reference frame.
  InitAttempt addFrame(const FrameContext& frame, const MapAnchor& anchor);
  // This frame is the reference of the next initialization (after a loss).
  void restartFrom(const FrameContext& frame);
  void reset() { pending_.clear(); }

 private:
  SystemConfig config_;
  double focal_px_;
  std::deque<PendingFrame> pending_;  // pending_.front() is the reference frame
};

}  // namespace vitamin_e::pipeline
