#pragma once
// A smooth, known car trajectory on flat ground for the street scene
// (street.h): a chain of legs, each straight or a turn, driven with a speed
// profile along the arc length. The camera sits camera_height above the road
// looking along the driving direction (optical z forward, x right, y down),
// with a small deterministic pitch/roll/height wobble (road unevenness).
//
// Geometry: a turn leg's curvature rises smoothly (sin^2 ramps) to a plateau
// and falls back, so heading, yaw rate and position are continuous; the speed
// blends from one leg's end speed to the next with a smoothstep in arc length,
// so acceleration is continuous too. Time follows from ds/dt = v(s).
#include <string>
#include <vector>

#include <Eigen/Geometry>

namespace vitamin_e::synth {

struct DriveLeg {
  enum class Kind { kStraight, kTurn };
  Kind kind = Kind::kStraight;
  double length_m = 10.0;      // arc length of the leg
  double end_speed = 2.0;      // speed at the end of the leg [m/s]
  double turn_rad = 0.0;       // turns: heading change, + = left (counter-clockwise seen from above)
  double ramp_fraction = 0.3;  // turns: curvature ramp-up (and ramp-down) length / leg length, in (0, 0.5]
};

struct DrivePathConfig {
  std::string name = "custom";
  Eigen::Vector2d start{0.0, 0.0};  // ground position at t = 0 [m]
  double heading0 = 0.0;            // driving direction at t = 0 (yaw about z, 0 = +x) [rad]
  double start_speed = 2.0;         // [m/s]
  std::vector<DriveLeg> legs;
  double camera_height = 1.65;  // above the road (z = 0) [m]
  double pitch0 = 0.0;          // camera pitch, + = up [rad]
  double pitch_amp = 0.004;     // wobble amplitudes [rad], [rad], [m]
  double roll_amp = 0.003;
  double height_amp = 0.01;
  void validate() const;  // throws std::invalid_argument naming the key
};

class DrivePath {
 public:
  explicit DrivePath(const DrivePathConfig& config);

  // Camera (optical) in the world (z up) at time t [s]; t is clamped to [0, duration()].
  Eigen::Isometry3d T_w_c(double t) const;
  Eigen::Vector3d position(double t) const;        // camera position
  Eigen::Vector2d groundPosition(double t) const;  // the car's (x, y), no wobble
  double heading(double t) const;                  // driving direction [rad], unwrapped
  double speed(double t) const;                    // [m/s]
  double yawRate(double t) const;                  // heading rate [rad/s] (curvature x speed)
  double arcLength(double t) const;                // distance driven since t = 0 [m]
  double timeAtArcLength(double s) const;          // inverse of arcLength [s]
  double duration() const { return duration_; }    // time to the end of the last leg [s]
  double length() const { return length_; }        // total arc length [m]
  // Start and end arc length of leg i.
  double legStart(int i) const { return leg_s0_[i]; }
  double legEnd(int i) const { return leg_s0_[i] + config_.legs[i].length_m; }
  // Camera positions every dt over [0, duration] (for keeping the scene clear of the path).
  std::vector<Eigen::Vector3d> samplePositions(double duration, double dt) const;
  const DrivePathConfig& config() const { return config_; }
  // Geometry at arc length s: curvature [1/m], heading, speed.
  double curvatureAt(double s) const;
  double headingAt(double s) const;
  double speedAt(double s) const;
  // One JSON object: name, start, legs, duration, length, camera mounting.
  std::string toJson() const;

 private:
  int legAt(double s) const;
  Eigen::Vector2d groundAt(double s) const;  // Hermite interpolation of the tabulated curve
  DrivePathConfig config_;
  std::vector<double> leg_s0_;
  double length_ = 0.0, duration_ = 0.0;
  double ds_ = 0.01;                    // arc-length step of the curve table [m]
  std::vector<Eigen::Vector2d> curve_;  // ground position every ds_
  double dt_ = 0.005;                   // time step of the s(t) table [s]
  std::vector<double> s_of_t_;          // arc length every dt_
};

// The named paths of the street scene (start at the origin heading +x, in the
// right lane of a street whose centre line is 1.5 m to the left):
//   "turn":  8 m straight slowing from 3 to 2 m/s, a 90-degree left turn at
//            walking speed (2 m/s, up to 3 degrees per frame at 10 Hz), 10 m
//            straight speeding up to 3.5 m/s.
//   "fast":  a 60 m straight accelerating from 5 to 15 m/s, then 45 m at 15 m/s.
//   "drive": KITTI 07-like: straight, left turn at walking speed, a fast
//            straight at up to 8.5 m/s, braking, right turn, straight.
//   "long":  "fast" with 240 m at 15 m/s after the 60 m of acceleration
//            (300 m, 23 s): many side streets passed at speed.
// Throws std::invalid_argument for another name (the message lists the names).
DrivePathConfig makeDrivePathConfig(const std::string& name);
std::vector<std::string> drivePathNames();

}  // namespace vitamin_e::synth
