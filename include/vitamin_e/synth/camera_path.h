#pragma once
// A smooth, known camera trajectory through the synthetic room: a horizontal
// figure-eight (lemniscate of Gerono) with a gentle height oscillation; the
// camera looks out at the walls, its heading turning slowly with small yaw,
// pitch and roll oscillations. Infinitely differentiable in time.
#include <vector>

#include <Eigen/Geometry>

namespace vitamin_e::synth {

struct CameraPathConfig {
  Eigen::Vector3d center{0.0, 0.0, 1.4};
  double radius_x = 1.2;       // half width of the figure-eight along x [m]
  double radius_y = 0.7;       // half height along y [m]
  double height_amp = 0.15;    // z oscillation [m]
  double speed = 0.4;          // mean speed along the path [m/s]
  double heading0 = 0.0;       // initial viewing direction (yaw about z) [rad]
  double heading_rate = 0.12;  // slow turn of the viewing direction [rad/s]
  double yaw_amp = 0.2;        // yaw oscillation [rad]
  double pitch0 = -0.12;       // looking slightly down [rad]
  double pitch_amp = 0.08;     // [rad]
  double roll_amp = 0.05;      // [rad]
  void validate() const;       // throws std::invalid_argument naming the key
};

class CameraPath {
 public:
  explicit CameraPath(const CameraPathConfig& config);
  // Camera (optical: x right, y down, z forward) in the world (z up) at time t [s].
  Eigen::Isometry3d T_w_c(double t) const;
  Eigen::Vector3d position(double t) const;
  // Positions every dt over [0, duration], for keeping boxes clear of the path.
  std::vector<Eigen::Vector3d> samplePositions(double duration, double dt) const;
  const CameraPathConfig& config() const { return config_; }
  double angularRate() const { return omega_; }  // path parameter rate [rad/s]

 private:
  CameraPathConfig config_;
  double omega_ = 0.0;
};

}  // namespace vitamin_e::synth
