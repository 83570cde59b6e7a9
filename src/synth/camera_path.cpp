#include "vitamin_e/synth/camera_path.h"

#include <cmath>
#include <stdexcept>

namespace vitamin_e::synth {

void CameraPathConfig::validate() const {
  if (!(radius_x > 0.0) || !(radius_y >= 0.0)) throw std::invalid_argument("radius_x must be > 0, radius_y >= 0");
  if (!(speed > 0.0 && speed < 20.0)) throw std::invalid_argument("speed must be in (0, 20) m/s");
  if (!(height_amp >= 0.0)) throw std::invalid_argument("height_amp must be >= 0");
  if (!(std::abs(pitch0) + pitch_amp < 1.2)) throw std::invalid_argument("pitch0 + pitch_amp must stay below 1.2 rad");
}

CameraPath::CameraPath(const CameraPathConfig& config) : config_(config) {
  config_.validate();
  // Path length of one period by numeric integration: omega = speed * 2 pi / length.
  const int n = 4000;
  double length = 0.0;
  omega_ = 1.0;
  Eigen::Vector3d prev = position(0.0);
  for (int i = 1; i <= n; ++i) {
    const Eigen::Vector3d p = position(2.0 * M_PI * i / n);
    length += (p - prev).norm();
    prev = p;
  }
  omega_ = config_.speed * 2.0 * M_PI / length;
}

Eigen::Vector3d CameraPath::position(double t) const {
  const double phi = omega_ * t;
  return config_.center + Eigen::Vector3d(config_.radius_x * std::sin(phi), config_.radius_y * std::sin(2.0 * phi),
                                          config_.height_amp * std::sin(3.0 * phi + 0.7));
}

Eigen::Isometry3d CameraPath::T_w_c(double t) const {
  const auto& c = config_;
  const double yaw = c.heading0 + c.heading_rate * t + c.yaw_amp * std::sin(0.31 * 2.0 * M_PI * t / 4.0);
  const double pitch = c.pitch0 + c.pitch_amp * std::sin(0.23 * 2.0 * M_PI * t / 2.0 + 1.1);
  const double roll = c.roll_amp * std::sin(0.17 * 2.0 * M_PI * t + 0.4);
  // Forward f (z_c), right r (x_c), down d = f x r (y_c) before roll.
  const Eigen::Vector3d f(std::cos(yaw) * std::cos(pitch), std::sin(yaw) * std::cos(pitch), std::sin(pitch));
  const Eigen::Vector3d r(std::sin(yaw), -std::cos(yaw), 0.0);
  const Eigen::Vector3d d = f.cross(r);
  Eigen::Matrix3d R_w_c;
  R_w_c << r, d, f;
  R_w_c = R_w_c * Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = R_w_c;
  T.translation() = position(t);
  return T;
}

std::vector<Eigen::Vector3d> CameraPath::samplePositions(double duration, double dt) const {
  std::vector<Eigen::Vector3d> out;
  for (double t = 0.0; t <= duration + 1e-9; t += dt) out.push_back(position(t));
  return out;
}

}  // namespace vitamin_e::synth
