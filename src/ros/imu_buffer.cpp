#include "vitamin_e/ros/imu_buffer.h"

#include <algorithm>
#include <cmath>

namespace vitamin_e_ros {

void ImuBuffer::add(double t, const Eigen::Vector3d& specific_force, const Eigen::Vector3d& angular_rate,
                    const std::string& frame_id) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (frame_.empty()) frame_ = frame_id;
  ++received_;
  if (gravity_.size() >= kMaxSamples) gravity_.dropBefore(gravity_.newest() - 10.0);
  gravity_.add(t, specific_force);
  if (!std::isfinite(t) || !angular_rate.allFinite()) return;
  if (!rates_.empty() && t <= rates_.back().t) {
    if (rates_.back().t - t <= 1.0) return;  // out of order
    rates_.clear();                          // the clock went back: start over
  }
  while (rates_.size() >= kMaxSamples) rates_.pop_front();
  rates_.push_back({t, angular_rate});
}

void ImuBuffer::dropBefore(double t) {
  std::lock_guard<std::mutex> lock(mutex_);
  gravity_.dropBefore(t);
  while (!rates_.empty() && rates_.front().t < t) rates_.pop_front();
}

std::string ImuBuffer::frame() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return frame_;
}

std::size_t ImuBuffer::received() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return received_;
}

GravityWindow::Estimate ImuBuffer::upInWorld(double t_end, double window_s,
                                             const std::function<Eigen::Matrix3d(double)>& R_w_c_at,
                                             const Eigen::Matrix3d& R_c_imu) const {
  std::lock_guard<std::mutex> lock(mutex_);
  return gravity_.upInWorld(t_end, window_s, R_w_c_at, R_c_imu);
}

bool ImuBuffer::rotationBetween(double t0, double t1, Eigen::Vector3d* theta_imu) const {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!(t1 > t0) || rates_.size() < 2 || rates_.front().t > t0 || rates_.back().t < t1) return false;
  // Each rate holds from its stamp to the next one's (zero-order hold), clipped to (t0, t1].
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  auto it = std::upper_bound(rates_.begin(), rates_.end(), t0, [](double t, const Rate& r) { return t < r.t; });
  if (it != rates_.begin()) --it;
  for (; it != rates_.end() && it->t < t1; ++it) {
    const double next = std::next(it) == rates_.end() ? t1 : std::next(it)->t;
    const double a = std::max(t0, it->t), b = std::min(t1, next);
    if (b > a) sum += it->w * (b - a);
  }
  *theta_imu = sum;
  return true;
}

void RotationAgreement::add(const Eigen::Vector3d& theta_c, const Eigen::Vector3d& theta_imu_in_c) {
  if (!theta_c.allFinite() || !theta_imu_in_c.allFinite()) return;
  ++intervals_;
  sum_c_ += theta_c.norm();
  sum_dot_ += theta_c.dot(theta_imu_in_c);
  sum_norms_ += theta_c.norm() * theta_imu_in_c.norm();
}

double RotationAgreement::cameraRotationDeg() const { return sum_c_ * 180.0 / M_PI; }

double RotationAgreement::meanAngleDeg() const {
  if (!(sum_norms_ > 0.0)) return 0.0;
  return std::acos(std::clamp(sum_dot_ / sum_norms_, -1.0, 1.0)) * 180.0 / M_PI;
}

std::optional<ImuRotationCheck::Verdict> ImuRotationCheck::add(bool pose_valid, double t, const Eigen::Matrix3d& R_w_c,
                                                               const GyroInCamera& gyro) {
  if (decided_) return std::nullopt;
  if (!pose_valid) {
    have_pose_ = false;
    return std::nullopt;
  }
  std::optional<Verdict> verdict;
  Eigen::Vector3d theta_gyro;
  if (have_pose_ && gyro(t_, t, &theta_gyro)) {
    const Eigen::AngleAxisd step(R_w_c_.transpose() * R_w_c);
    agreement_.add(step.angle() * step.axis(), theta_gyro);
    if (agreement_.cameraRotationDeg() >= kMinRotationDeg && agreement_.intervals() >= kMinIntervals) {
      decided_ = true;
      verdict = Verdict{agreement_.meanAngleDeg() <= kMaxMeanAngleDeg, agreement_.meanAngleDeg(),
                        agreement_.cameraRotationDeg(), agreement_.intervals()};
    }
  }
  have_pose_ = true;
  t_ = t;
  R_w_c_ = R_w_c;
  return verdict;
}

}  // namespace vitamin_e_ros
