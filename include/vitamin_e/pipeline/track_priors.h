#pragma once
// Where the map expects the tracks in the next frame: the map points of the
// last localized frame, seen from the motion model's pose at the new frame's
// time. The mapping stage makes the source after each frame; the tracking stage
// turns it into the tracker's priors (it may be a frame or two behind in
// pipelined mode: the motion model predicts across the gap).
#include <Eigen/Core>
#include <cstdint>
#include <utility>
#include <vector>

#include "vitamin_e/camera/camera.h"
#include "vitamin_e/pipeline/motion_model.h"
#include "vitamin_e/tracking/dense_tracker.h"

namespace vitamin_e::pipeline {

struct TrackPriorSource {
  MotionModel motion;                                                   // valid
  std::vector<std::pair<std::uint64_t, Eigen::Vector3d>> p_w_by_track;  // sorted by track id
};

// The priors at `timestamp`, sorted by track id: points behind the camera or
// outside the image have none.
std::vector<tracking::TrackPrior> predictTrackPositions(const TrackPriorSource& source, const camera::Camera& camera,
                                                        double timestamp);

}  // namespace vitamin_e::pipeline
