#include "vitamin_e/ros/map_frame.h"

#include <algorithm>
#include <cmath>

namespace vitamin_e_ros {

namespace {

Eigen::Isometry3d fromAxes(const Eigen::Vector3d& x_w, const Eigen::Vector3d& y_w, const Eigen::Vector3d& z_w,
                           const Eigen::Vector3d& origin_w) {
  // Rows of R_map_w are the map axes in the world: p_map = R_map_w (p_w - origin_w).
  Eigen::Matrix3d R_map_w;
  R_map_w.row(0) = x_w.transpose();
  R_map_w.row(1) = y_w.transpose();
  R_map_w.row(2) = z_w.transpose();
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = R_map_w;
  T.translation() = -R_map_w * origin_w;
  return T;
}

}  // namespace

Eigen::Isometry3d mapFromUp(const Eigen::Vector3d& up_w, const Eigen::Isometry3d& T_w_c0) {
  const Eigen::Vector3d z = up_w.normalized();
  Eigen::Vector3d x = T_w_c0.linear().col(2);  // viewing direction
  x -= x.dot(z) * z;
  if (x.norm() < 1e-3) {  // looking along gravity: the camera's up (-y) gives the heading
    x = -T_w_c0.linear().col(1);
    x -= x.dot(z) * z;
  }
  x.normalize();
  const Eigen::Vector3d y = z.cross(x);
  return fromAxes(x, y, z, T_w_c0.translation());
}

Eigen::Isometry3d mapFromCameraAxes(const Eigen::Isometry3d& T_w_c0) {
  const Eigen::Matrix3d& R = T_w_c0.linear();
  return fromAxes(R.col(2), -R.col(0), -R.col(1), T_w_c0.translation());
}

Eigen::Isometry3d mapFromBase(const Eigen::Isometry3d& T_base_cam, const Eigen::Isometry3d& T_w_c0) {
  return T_base_cam * T_w_c0.inverse();
}

Eigen::Matrix3d orientationAt(const std::vector<vitamin_e::pipeline::TrajectoryEntry>& trajectory, double t) {
  if (trajectory.empty()) return Eigen::Matrix3d::Identity();
  auto later =
      std::lower_bound(trajectory.begin(), trajectory.end(), t,
                       [](const vitamin_e::pipeline::TrajectoryEntry& e, double v) { return e.timestamp < v; });
  if (later == trajectory.begin()) return later->T_w_c.rotation();
  if (later == trajectory.end()) return trajectory.back().T_w_c.rotation();
  const auto& a = *(later - 1);
  const auto& b = *later;
  const double span = b.timestamp - a.timestamp;
  const double s = span > 0.0 ? std::clamp((t - a.timestamp) / span, 0.0, 1.0) : 0.0;
  const Eigen::Quaterniond qa(a.T_w_c.rotation()), qb(b.T_w_c.rotation());
  return qa.slerp(s, qb).toRotationMatrix();
}

void GravityWindow::add(double t, const Eigen::Vector3d& f_imu) {
  if (!std::isfinite(t) || !f_imu.allFinite()) return;
  if (!samples_.empty() && t <= samples_.back().t) {
    if (samples_.back().t - t <= 1.0) return;  // out of order
    samples_.clear();                          // the clock went back (a bag played again): start over
  }
  samples_.push_back({t, f_imu});
}

void GravityWindow::dropBefore(double t) {
  while (!samples_.empty() && samples_.front().t < t) samples_.pop_front();
}

GravityWindow::Estimate GravityWindow::upInWorld(double t_end, double window_s,
                                                 const std::function<Eigen::Matrix3d(double)>& R_w_c_at,
                                                 const Eigen::Matrix3d& R_c_imu, int min_samples) const {
  Estimate e;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  double first = 0.0, last = 0.0;
  for (const Sample& s : samples_) {
    if (s.t < t_end - window_s || s.t > t_end) continue;
    if (e.samples == 0) first = s.t;
    last = s.t;
    sum += R_w_c_at(s.t) * (R_c_imu * s.f);
    ++e.samples;
  }
  e.span_s = e.samples > 0 ? last - first : 0.0;
  if (e.samples < min_samples) {
    e.message = std::to_string(e.samples) + " accelerometer samples in the " + std::to_string(window_s) +
                " s before the initialization (" + std::to_string(samples_.size()) + " buffered)";
    return e;
  }
  const Eigen::Vector3d mean = sum / e.samples;
  e.magnitude = mean.norm();
  if (!(e.magnitude > 1e-6)) {
    e.message = "the mean specific force is zero (free fall or no accelerometer data)";
    return e;
  }
  e.up_w = mean / e.magnitude;
  e.ok = true;
  return e;
}

Matrix6d covarianceInParent(const Matrix6d& cov_right, const Eigen::Matrix3d& R_p_c) {
  // T exp(delta) to first order: position t + R rho, orientation exp([R phi]x) R.
  Matrix6d J = Matrix6d::Zero();
  J.topLeftCorner<3, 3>() = R_p_c;
  J.bottomRightCorner<3, 3>() = R_p_c;
  return J * cov_right * J.transpose();
}

Matrix6d covarianceMovedTo(const Matrix6d& cov_parent, const Eigen::Vector3d& lever_p) {
  // t_child = t_cam + R lever: a rotation error phi adds phi x lever = -[lever]x phi.
  Matrix6d J = Matrix6d::Identity();
  Eigen::Matrix3d skew;
  skew << 0, -lever_p.z(), lever_p.y(), lever_p.z(), 0, -lever_p.x(), -lever_p.y(), lever_p.x(), 0;
  J.topRightCorner<3, 3>() = -skew;
  return J * cov_parent * J.transpose();
}

}  // namespace vitamin_e_ros
