#pragma once
// What the SLAM system returns for every input frame. Plain data, no ROS: the
// ROS layer and the offline runner turn it into messages and files.
#include <Eigen/Geometry>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace vitamin_e::pipeline {

enum class TrackingState {
  kInitializing,  // waiting for enough parallax to build the first map
  kTracking,      // pose estimated for this frame
  kLost,          // tracking failed at this frame; the system relocalizes (or re-initializes)
  kRelocalizing,  // lost: looking for the camera in the existing map (no pose this frame)
};

const char* toString(TrackingState state);

// One densely tracked point of the current frame.
struct FramePoint {
  std::uint64_t track_id = 0;   // stable over the frames the point is tracked
  Eigen::Vector2f uv;           // pixel in the (distorted) input image
  bool has_position = false;    // true once triangulated
  Eigen::Vector3d p_w = Eigen::Vector3d::Zero();  // map position (world frame)
  std::uint8_t intensity = 0;   // image intensity at uv
};

struct FrameResult {
  std::uint64_t frame_index = 0;   // 0-based index of the frame in the stream
  double timestamp = 0.0;          // seconds, as given to process()
  TrackingState state = TrackingState::kInitializing;
  bool pose_valid = false;         // T_w_c is meaningful (state == kTracking)
  Eigen::Isometry3d T_w_c = Eigen::Isometry3d::Identity();  // camera (optical) in world
  // Covariance of T_w_c from the per-frame BA (optimization::BaSummary::camera_covariance): of
  // the right perturbation delta = (rho, phi), T_w_c * expSE3(delta), in the camera frame, map
  // units^2 and rad^2, relative to the fixed keyframes. Meaningful only when the flag is set.
  Eigen::Matrix<double, 6, 6> T_w_c_covariance = Eigen::Matrix<double, 6, 6>::Zero();
  bool T_w_c_covariance_valid = false;
  std::vector<FramePoint> points;  // tracked points of this frame
  std::size_t num_tracked = 0;     // 2D tracks alive
  std::size_t num_mapped = 0;      // tracks with a 3D position
  std::size_t map_size = 0;        // points in the map
  int init_retries = 0;            // re-initializations so far (each one a new map)
  int relocalizations = 0;         // losses recovered in the existing map so far
  std::map<std::string, double> timing_ms;  // this frame's per-stage times
  std::string message;             // a human-readable note (why lost, why waiting)
};

}  // namespace vitamin_e::pipeline
