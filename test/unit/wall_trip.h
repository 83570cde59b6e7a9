#pragma once
// The sideways trip along a textured wall shared by the system tests of map
// reuse (out and back) and of planar initialization (out only, wall filling
// the view), both on the project's renders at 376x240.
#include <cmath>

#include <Eigen/Geometry>

#include "vitamin_e/pipeline/system.h"

namespace vitamin_e::test {

// The camera at time t [s] of a round trip lasting round_trip_s: x goes from
// -trip_m/2 to +trip_m/2 and back (cosine profile, at rest at both ends) at
// y = 1 m, 2 m from the room's +y wall, facing it and pitched down by -pitch
// rad, with a small height and yaw wobble so that outbound and return views
// are not pixel copies of each other.
inline Eigen::Isometry3d wallTripPose(double t, double round_trip_s, double trip_m, double pitch) {
  const double phase = 2.0 * M_PI * t / round_trip_s;
  const double s = 0.5 * (1.0 - std::cos(phase));
  const Eigen::Vector3d position(-0.5 * trip_m + trip_m * s, 1.0, 1.4 + 0.1 * std::sin(phase));
  const double yaw = 0.5 * M_PI + 0.05 * std::sin(3.0 * t);
  const Eigen::Vector3d forward(std::cos(yaw) * std::cos(pitch), std::sin(yaw) * std::cos(pitch), std::sin(pitch));
  const Eigen::Vector3d right(std::sin(yaw), -std::cos(yaw), 0.0);
  Eigen::Isometry3d T_w_c = Eigen::Isometry3d::Identity();
  T_w_c.linear() << right, forward.cross(right), forward;  // optical: x right, y down, z forward
  T_w_c.translation() = position;
  return T_w_c;
}

// The system defaults with the pixel thresholds that are tuned at 752x480
// halved for 376x240 (as in test_system_robustness).
inline pipeline::SystemConfig halfResolutionConfig() {
  pipeline::SystemConfig config;
  config.init_min_disparity_px = 10.0;
  config.keyframe_parallax_px = 10.0;
  config.min_init_track_budget_fraction = 100.0 / config.tracker.max_points;
  return config;
}

}  // namespace vitamin_e::test
