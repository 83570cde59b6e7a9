#include "vitamin_e/synth/drive_path.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace vitamin_e::synth {

namespace {

constexpr double kDeg = M_PI / 180.0;

double smoothstep(double u) { return u * u * (3.0 - 2.0 * u); }

// Curvature profile of a turn over u in [0, 1] (fraction of the leg): sin^2
// ramps of length r up to 1 and back down; its integral over [0, 1] is 1 - r.
double profile(double u, double r) {
  if (u < r) return std::pow(std::sin(0.5 * M_PI * u / r), 2);
  if (u > 1.0 - r) return std::pow(std::sin(0.5 * M_PI * (1.0 - u) / r), 2);
  return 1.0;
}

// Integral of profile from 0 to u.
double profileIntegral(double u, double r) {
  auto ramp = [r](double w) { return 0.5 * w - r / (2.0 * M_PI) * std::sin(M_PI * w / r); };
  if (u < r) return ramp(u);
  if (u > 1.0 - r) return (1.0 - r) - ramp(1.0 - u);
  return 0.5 * r + (u - r);
}

}  // namespace

void DrivePathConfig::validate() const {
  if (legs.empty()) throw std::invalid_argument("drive path: legs must not be empty");
  if (!(start_speed >= 0.1 && start_speed <= 40.0))
    throw std::invalid_argument("drive path: start_speed must be in [0.1, 40] m/s");
  for (std::size_t i = 0; i < legs.size(); ++i) {
    const DriveLeg& l = legs[i];
    const std::string at = "drive path: leg " + std::to_string(i) + ": ";
    if (!(l.length_m > 0.0 && l.length_m <= 5000.0)) throw std::invalid_argument(at + "length_m must be in (0, 5000]");
    if (!(l.end_speed >= 0.1 && l.end_speed <= 40.0))
      throw std::invalid_argument(at + "end_speed must be in [0.1, 40] m/s");
    if (l.kind == DriveLeg::Kind::kTurn) {
      if (!(std::abs(l.turn_rad) > 0.0 && std::abs(l.turn_rad) <= M_PI))
        throw std::invalid_argument(at + "turn_rad must be in [-pi, pi], not 0");
      if (!(l.ramp_fraction > 0.0 && l.ramp_fraction <= 0.5))
        throw std::invalid_argument(at + "ramp_fraction must be in (0, 0.5]");
    } else if (l.turn_rad != 0.0) {
      throw std::invalid_argument(at + "a straight leg has turn_rad 0");
    }
  }
  if (!(camera_height > 0.2 && camera_height < 10.0))
    throw std::invalid_argument("drive path: camera_height must be in (0.2, 10) m");
  if (!(std::abs(pitch0) + pitch_amp < 0.5))
    throw std::invalid_argument("drive path: pitch0 + pitch_amp must stay below 0.5 rad");
  if (!(pitch_amp >= 0.0 && roll_amp >= 0.0 && roll_amp < 0.2 && height_amp >= 0.0 && height_amp < 0.5))
    throw std::invalid_argument("drive path: wobble amplitudes must be >= 0 (roll < 0.2 rad, height < 0.5 m)");
  if (!std::isfinite(heading0) || !start.allFinite())
    throw std::invalid_argument("drive path: start and heading0 must be finite");
}

DrivePath::DrivePath(const DrivePathConfig& config) : config_(config) {
  config_.validate();
  double s = 0.0;
  for (const DriveLeg& l : config_.legs) {
    leg_s0_.push_back(s);
    s += l.length_m;
  }
  length_ = s;
  // The ground curve every ds_ by Simpson's rule on the closed-form heading.
  const int n = static_cast<int>(std::ceil(length_ / ds_));
  ds_ = length_ / n;
  curve_.resize(n + 1);
  curve_[0] = config_.start;
  auto tangent = [this](double at) {
    const double h = headingAt(at);
    return Eigen::Vector2d(std::cos(h), std::sin(h));
  };
  for (int i = 0; i < n; ++i) {
    const double a = i * ds_;
    curve_[i + 1] = curve_[i] + ds_ / 6.0 * (tangent(a) + 4.0 * tangent(a + 0.5 * ds_) + tangent(a + ds_));
  }
  // Arc length over time: RK4 on ds/dt = v(s) until the end of the path.
  s_of_t_.push_back(0.0);
  double cur = 0.0;
  auto v = [this](double at) { return speedAt(std::min(at, length_)); };
  while (cur < length_) {
    const double k1 = v(cur), k2 = v(cur + 0.5 * dt_ * k1), k3 = v(cur + 0.5 * dt_ * k2), k4 = v(cur + dt_ * k3);
    cur += dt_ / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
    s_of_t_.push_back(cur);
    if (s_of_t_.size() > 50000000) throw std::invalid_argument("drive path: too long (more than 250000 s)");
  }
  // The last step overshoots: the end time by linear interpolation in it.
  const std::size_t m = s_of_t_.size() - 1;
  duration_ = dt_ * (static_cast<double>(m - 1) + (length_ - s_of_t_[m - 1]) / (s_of_t_[m] - s_of_t_[m - 1]));
}

int DrivePath::legAt(double s) const {
  const auto it = std::upper_bound(leg_s0_.begin(), leg_s0_.end(), s);
  return std::max(0, static_cast<int>(it - leg_s0_.begin()) - 1);
}

double DrivePath::curvatureAt(double s) const {
  s = std::clamp(s, 0.0, length_);
  const int i = legAt(s);
  const DriveLeg& l = config_.legs[i];
  if (l.kind != DriveLeg::Kind::kTurn) return 0.0;
  const double u = std::clamp((s - leg_s0_[i]) / l.length_m, 0.0, 1.0);
  return l.turn_rad / (l.length_m * (1.0 - l.ramp_fraction)) * profile(u, l.ramp_fraction);
}

double DrivePath::headingAt(double s) const {
  s = std::clamp(s, 0.0, length_);
  const int i = legAt(s);
  double h = config_.heading0;
  for (int k = 0; k < i; ++k) h += config_.legs[k].turn_rad;
  const DriveLeg& l = config_.legs[i];
  if (l.kind == DriveLeg::Kind::kTurn) {
    const double u = std::clamp((s - leg_s0_[i]) / l.length_m, 0.0, 1.0);
    h += l.turn_rad * profileIntegral(u, l.ramp_fraction) / (1.0 - l.ramp_fraction);
  }
  return h;
}

double DrivePath::speedAt(double s) const {
  s = std::clamp(s, 0.0, length_);
  const int i = legAt(s);
  const DriveLeg& l = config_.legs[i];
  const double v0 = i == 0 ? config_.start_speed : config_.legs[i - 1].end_speed;
  const double u = std::clamp((s - leg_s0_[i]) / l.length_m, 0.0, 1.0);
  return v0 + (l.end_speed - v0) * smoothstep(u);
}

Eigen::Vector2d DrivePath::groundAt(double s) const {
  s = std::clamp(s, 0.0, length_);
  const int n = static_cast<int>(curve_.size()) - 1;
  const int i = std::min(n - 1, static_cast<int>(s / ds_));
  const double a = (s - i * ds_) / ds_;
  // Cubic Hermite with the unit tangents (the derivative along arc length).
  const double h0 = headingAt(i * ds_), h1 = headingAt((i + 1) * ds_);
  const Eigen::Vector2d m0 = ds_ * Eigen::Vector2d(std::cos(h0), std::sin(h0));
  const Eigen::Vector2d m1 = ds_ * Eigen::Vector2d(std::cos(h1), std::sin(h1));
  const double a2 = a * a, a3 = a2 * a;
  return (2 * a3 - 3 * a2 + 1) * curve_[i] + (a3 - 2 * a2 + a) * m0 + (-2 * a3 + 3 * a2) * curve_[i + 1] +
         (a3 - a2) * m1;
}

double DrivePath::arcLength(double t) const {
  t = std::clamp(t, 0.0, duration_);
  const int m = static_cast<int>(s_of_t_.size()) - 1;
  const int i = std::min(m - 1, static_cast<int>(t / dt_));
  const double a = (t - i * dt_) / dt_;
  const double s0 = s_of_t_[i], s1 = s_of_t_[i + 1];
  const double m0 = dt_ * speedAt(s0), m1 = dt_ * speedAt(s1);
  const double a2 = a * a, a3 = a2 * a;
  return std::min(length_,
                  (2 * a3 - 3 * a2 + 1) * s0 + (a3 - 2 * a2 + a) * m0 + (-2 * a3 + 3 * a2) * s1 + (a3 - a2) * m1);
}

double DrivePath::timeAtArcLength(double s) const {
  s = std::clamp(s, 0.0, length_);
  const auto it = std::upper_bound(s_of_t_.begin(), s_of_t_.end(), s);
  const int i = std::clamp(static_cast<int>(it - s_of_t_.begin()) - 1, 0, static_cast<int>(s_of_t_.size()) - 2);
  // Newton on the Hermite segment, from the linear guess.
  double t = (i + (s - s_of_t_[i]) / std::max(1e-12, s_of_t_[i + 1] - s_of_t_[i])) * dt_;
  for (int k = 0; k < 4; ++k) t -= (arcLength(t) - s) / std::max(1e-6, speedAt(arcLength(t)));
  return std::clamp(t, 0.0, duration_);
}

Eigen::Vector2d DrivePath::groundPosition(double t) const { return groundAt(arcLength(t)); }
double DrivePath::heading(double t) const { return headingAt(arcLength(t)); }
double DrivePath::speed(double t) const { return speedAt(arcLength(t)); }
double DrivePath::yawRate(double t) const {
  const double s = arcLength(t);
  return curvatureAt(s) * speedAt(s);
}

Eigen::Vector3d DrivePath::position(double t) const {
  const double s = arcLength(t);
  const Eigen::Vector2d g = groundAt(s);
  // Road unevenness: spatial wavelengths (7.3, 11.1, 4.7 m), so a car at rest does not bob.
  return Eigen::Vector3d(g.x(), g.y(),
                         config_.camera_height + config_.height_amp * std::sin(2.0 * M_PI * s / 4.7 + 0.4));
}

Eigen::Isometry3d DrivePath::T_w_c(double t) const {
  const auto& c = config_;
  const double s = arcLength(t);
  const double yaw = headingAt(s);
  const double pitch = c.pitch0 + c.pitch_amp * std::sin(2.0 * M_PI * s / 7.3 + 0.3);
  const double roll = c.roll_amp * std::sin(2.0 * M_PI * s / 11.1 + 1.1);
  // Forward f (z_c), right r (x_c), down d = f x r (y_c) before roll.
  const Eigen::Vector3d f(std::cos(yaw) * std::cos(pitch), std::sin(yaw) * std::cos(pitch), std::sin(pitch));
  const Eigen::Vector3d r(std::sin(yaw), -std::cos(yaw), 0.0);
  Eigen::Matrix3d R_w_c;
  R_w_c << r, f.cross(r), f;
  R_w_c = R_w_c * Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = R_w_c;
  T.translation() = position(t);
  return T;
}

std::vector<Eigen::Vector3d> DrivePath::samplePositions(double duration, double dt) const {
  std::vector<Eigen::Vector3d> out;
  for (double t = 0.0; t <= duration + 1e-9; t += dt) out.push_back(position(t));
  return out;
}

std::string DrivePath::toJson() const {
  std::ostringstream o;
  o.precision(9);
  o << "{\"kind\": \"drive\", \"name\": \"" << config_.name << "\", \"start\": [" << config_.start.x() << ", "
    << config_.start.y() << "], \"heading0\": " << config_.heading0 << ", \"start_speed_m_s\": " << config_.start_speed
    << ", \"length_m\": " << length_ << ", \"duration_s\": " << duration_
    << ", \"camera_height_m\": " << config_.camera_height << ", \"pitch0\": " << config_.pitch0
    << ", \"pitch_amp\": " << config_.pitch_amp << ", \"roll_amp\": " << config_.roll_amp
    << ", \"height_amp_m\": " << config_.height_amp << ",\n  \"legs\": [";
  for (std::size_t i = 0; i < config_.legs.size(); ++i) {
    const DriveLeg& l = config_.legs[i];
    o << (i ? ", " : "") << "{\"kind\": \"" << (l.kind == DriveLeg::Kind::kTurn ? "turn" : "straight")
      << "\", \"length_m\": " << l.length_m << ", \"end_speed_m_s\": " << l.end_speed;
    if (l.kind == DriveLeg::Kind::kTurn)
      o << ", \"turn_deg\": " << l.turn_rad / kDeg << ", \"ramp_fraction\": " << l.ramp_fraction;
    o << "}";
  }
  o << "]}";
  return o.str();
}

std::vector<std::string> drivePathNames() { return {"turn", "fast", "drive", "long"}; }

DrivePathConfig makeDrivePathConfig(const std::string& name) {
  DrivePathConfig c;
  c.name = name;
  auto straight = [](double length, double end_speed) {
    DriveLeg l;
    l.length_m = length;
    l.end_speed = end_speed;
    return l;
  };
  // A 90-degree turn at v m/s peaking at 3 degrees per 0.1 s frame (30 deg/s):
  // peak curvature = 30 deg/s / v, and the leg length follows from the angle
  // and the ramps (the curvature integrates to the turn angle).
  auto turn = [](double degrees, double v) {
    DriveLeg l;
    l.kind = DriveLeg::Kind::kTurn;
    l.turn_rad = degrees * kDeg;
    l.end_speed = v;
    l.ramp_fraction = 0.3;
    const double peak_curvature = 30.0 * kDeg / v;
    l.length_m = std::abs(l.turn_rad) / (peak_curvature * (1.0 - l.ramp_fraction));
    return l;
  };
  if (name == "turn") {
    c.start_speed = 3.0;
    c.legs = {straight(10.0, 2.0), turn(90.0, 2.0), straight(10.0, 3.5)};
  } else if (name == "fast") {
    c.start_speed = 5.0;
    c.legs = {straight(60.0, 15.0), straight(45.0, 15.0)};
  } else if (name == "long") {
    c.start_speed = 5.0;
    c.legs = {straight(60.0, 15.0), straight(240.0, 15.0)};
  } else if (name == "drive") {
    c.start_speed = 3.0;
    c.legs = {straight(15.0, 2.0), turn(90.0, 2.0),  straight(30.0, 8.5), straight(40.0, 8.5),
              straight(20.0, 2.0), turn(-90.0, 2.0), straight(15.0, 4.0)};
  } else {
    std::string names;
    for (const auto& n : drivePathNames()) names += (names.empty() ? "" : ", ") + n;
    throw std::invalid_argument("unknown drive path '" + name + "' (one of " + names + ")");
  }
  return c;
}

}  // namespace vitamin_e::synth
