#pragma once
// The published map frame. The SLAM core keeps its world frame w: the
// first reference camera's optical frame (z forward, y down), arbitrary scale. The ROS layer
// publishes everything in a map frame fixed once per SLAM run, T_map_w, chosen from (best
// first) gravity measured by an IMU, the robot's base frame, or the first camera's axes.
// Plain Eigen: no ROS types, unit-tested without a master.
#include <deque>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "vitamin_e/pipeline/system.h"

namespace vitamin_e_ros {

using Matrix6d = Eigen::Matrix<double, 6, 6>;

// z_map = up_w (normalized), x_map = the first camera's viewing direction (optical z of
// T_w_c0) made horizontal, origin at the first camera. Falls back to the camera's -y (its
// "up") made horizontal when the camera looks straight up or down.
Eigen::Isometry3d mapFromUp(const Eigen::Vector3d& up_w, const Eigen::Isometry3d& T_w_c0);
// The first camera in ROS axes (REP-103 body: x forward, y left, z up): x_map = optical z,
// y_map = -optical x, z_map = -optical y, origin at the camera. As level as that camera.
Eigen::Isometry3d mapFromCameraAxes(const Eigen::Isometry3d& T_w_c0);
// The base (robot) pose when the first camera was at T_w_c0: map = base at that moment
// (REP-105), T_map_w = T_base_cam * T_w_c0^-1.
Eigen::Isometry3d mapFromBase(const Eigen::Isometry3d& T_base_cam, const Eigen::Isometry3d& T_w_c0);

// Camera orientation R_w_c at time t from a trajectory sorted by time: slerp between the two
// neighbouring poses, the end pose outside its span. Identity for an empty trajectory.
Eigen::Matrix3d orientationAt(const std::vector<vitamin_e::pipeline::TrajectoryEntry>& trajectory, double t);

// Accelerometer samples (specific force in the IMU frame, m/s^2) kept for the map's gravity:
// the direction "up" is the mean specific force over a window, each sample rotated into the
// world by the camera orientation at its time (the camera moves during the window).
class GravityWindow {
 public:
  // In time order: a sample older than the newest is ignored, unless by more than 1 s (the
  // clock went back, e.g. a bag played again): then the window starts over.
  void add(double t, const Eigen::Vector3d& f_imu);
  void dropBefore(double t);
  void clear() { samples_.clear(); }
  std::size_t size() const { return samples_.size(); }
  double newest() const { return samples_.empty() ? -1e300 : samples_.back().t; }

  struct Estimate {
    bool ok = false;
    Eigen::Vector3d up_w = Eigen::Vector3d::Zero();  // unit
    int samples = 0;
    double span_s = 0.0;     // time covered by the samples used
    double magnitude = 0.0;  // |mean specific force| (9.81 at rest or in steady flight)
    std::string message;     // why not ok
  };
  // Mean of R_w_c(t) R_c_imu f over the samples in [t_end - window_s, t_end].
  Estimate upInWorld(double t_end, double window_s, const std::function<Eigen::Matrix3d(double)>& R_w_c_at,
                     const Eigen::Matrix3d& R_c_imu, int min_samples = 10) const;

 private:
  struct Sample {
    double t;
    Eigen::Vector3d f;
  };
  std::deque<Sample> samples_;
};

// Pose covariance of the core (6x6 of the right perturbation (rho, phi) of T_p_c, camera
// frame) -> ROS's PoseWithCovariance convention: position and small rotation errors about the
// parent frame's axes, (x y z rx ry rz). R_p_c: the camera's orientation in the parent frame.
Matrix6d covarianceInParent(const Matrix6d& cov_right, const Eigen::Matrix3d& R_p_c);
// The same for a child frame rigidly attached to the camera (the base): its origin is at
// lever_p = R_p_c * t_c_child from the camera, so a rotation error moves it by phi x lever_p.
Matrix6d covarianceMovedTo(const Matrix6d& cov_parent, const Eigen::Vector3d& lever_p);

}  // namespace vitamin_e_ros
