// Drive paths of the street scene (drive_path.h): the speeds and turn rates
// are those configured, measured from the poses themselves (finite
// differences), the motion is smooth, the camera looks along the driving
// direction at its mounting height, and bad configurations are refused.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>

#include "vitamin_e/synth/drive_path.h"

namespace vs = vitamin_e::synth;

namespace {

constexpr double kDeg = M_PI / 180.0;

// Speed from the positions: central difference over 2 ms.
double measuredSpeed(const vs::DrivePath& p, double t) {
  const double h = 1e-3;
  const double a = std::max(0.0, t - h), b = std::min(p.duration(), t + h);
  return (p.groundPosition(b) - p.groundPosition(a)).norm() / (b - a);
}

// Heading rate from the direction of motion: central difference over 2 ms.
double measuredYawRate(const vs::DrivePath& p, double t) {
  const double h = 1e-3;
  auto dir = [&](double at) {
    const Eigen::Vector2d v = p.groundPosition(at + 1e-4) - p.groundPosition(at - 1e-4);
    return std::atan2(v.y(), v.x());
  };
  double d = dir(t + h) - dir(t - h);
  d = std::remainder(d, 2.0 * M_PI);
  return d / (2.0 * h);
}

// Rotation angle between the camera poses at 10 Hz frames i and i+1 [deg].
double frameRotationDeg(const vs::DrivePath& p, int i) {
  const Eigen::Isometry3d d = p.T_w_c(i / 10.0).inverse() * p.T_w_c((i + 1) / 10.0);
  return Eigen::AngleAxisd(d.rotation()).angle() / kDeg;
}

}  // namespace

TEST(SynthDrivePath, TurnHasTheConfiguredSpeedsAndTurnRate) {
  const vs::DrivePath p(vs::makeDrivePathConfig("turn"));
  const auto& legs = p.config().legs;
  ASSERT_EQ(legs.size(), 3u);
  EXPECT_EQ(legs[1].kind, vs::DriveLeg::Kind::kTurn);
  EXPECT_NEAR(p.length(), 10.0 + legs[1].length_m + 10.0, 1e-9);
  // Speeds at the leg ends, and constant walking speed through the turn.
  EXPECT_NEAR(measuredSpeed(p, 0.0), 3.0, 2e-3);
  EXPECT_NEAR(measuredSpeed(p, p.duration()), 3.5, 2e-3);
  const double t_in = p.timeAtArcLength(p.legStart(1)), t_out = p.timeAtArcLength(p.legEnd(1));
  for (double t = t_in; t <= t_out; t += 0.05) EXPECT_NEAR(measuredSpeed(p, t), 2.0, 1e-3) << "t " << t;
  // The measured motion agrees with the path's own speed and yaw rate everywhere.
  double max_yaw_rate = 0.0;
  for (double t = 0.01; t < p.duration() - 0.01; t += 0.03) {
    ASSERT_NEAR(measuredSpeed(p, t), p.speed(t), 2e-3) << "t " << t;
    ASSERT_NEAR(measuredYawRate(p, t), p.yawRate(t), 2e-3) << "t " << t;
    max_yaw_rate = std::max(max_yaw_rate, p.yawRate(t));
  }
  // Peak 30 deg/s at 2 m/s (3 degrees per 10 Hz frame), a left turn of 90 degrees.
  EXPECT_NEAR(max_yaw_rate, 30.0 * kDeg, 1e-3);
  EXPECT_NEAR(p.heading(p.duration()) - p.heading(0.0), 90.0 * kDeg, 1e-9);
  const Eigen::Vector2d end_dir = p.groundPosition(p.duration()) - p.groundPosition(p.duration() - 0.1);
  EXPECT_NEAR(std::atan2(end_dir.y(), end_dir.x()), 90.0 * kDeg, 1e-4);
  // At 10 Hz: 0.2 - 0.35 m per frame, up to 3 degrees of rotation (wobble included).
  double max_rot = 0.0;
  for (int i = 0; (i + 1) / 10.0 <= p.duration(); ++i) {
    const double step = (p.position((i + 1) / 10.0) - p.position(i / 10.0)).norm();
    EXPECT_GE(step, 0.19) << "frame " << i;
    EXPECT_LE(step, 0.36) << "frame " << i;
    max_rot = std::max(max_rot, frameRotationDeg(p, i));
  }
  EXPECT_GT(max_rot, 2.8);
  EXPECT_LT(max_rot, 3.1);
}

TEST(SynthDrivePath, FastAcceleratesToFifteenMetresPerSecond) {
  const vs::DrivePath p(vs::makeDrivePathConfig("fast"));
  EXPECT_NEAR(measuredSpeed(p, 0.0), 5.0, 2e-3);
  double prev = 0.0, max_speed = 0.0;
  for (double t = 0.0; t <= p.duration(); t += 0.05) {
    const double v = measuredSpeed(p, t);
    EXPECT_GE(v, prev - 1e-3) << "slowing down at t " << t;  // never slows down
    prev = v;
    max_speed = std::max(max_speed, v);
    EXPECT_NEAR(p.yawRate(t), 0.0, 1e-12);
  }
  EXPECT_NEAR(max_speed, 15.0, 2e-3);
  // 15 m/s over the last 45 m.
  for (double s = 61.0; s < p.length(); s += 5.0) EXPECT_NEAR(p.speedAt(s), 15.0, 1e-9);
  EXPECT_NEAR(p.length(), 105.0, 1e-9);
  // Straight along +x, in its lane (y = 0).
  EXPECT_NEAR(p.groundPosition(p.duration()).x(), 105.0, 1e-6);
  EXPECT_NEAR(p.groundPosition(p.duration()).y(), 0.0, 1e-9);
}

TEST(SynthDrivePath, DriveIsStraightTurnFastStraightTurn) {
  const vs::DrivePath p(vs::makeDrivePathConfig("drive"));
  double max_speed = 0.0, max_yaw = 0.0, min_yaw = 0.0;
  for (double t = 0.0; t <= p.duration(); t += 0.05) {
    max_speed = std::max(max_speed, p.speed(t));
    max_yaw = std::max(max_yaw, p.yawRate(t));
    min_yaw = std::min(min_yaw, p.yawRate(t));
  }
  EXPECT_NEAR(max_speed, 8.5, 1e-6);
  EXPECT_NEAR(max_yaw, 30.0 * kDeg, 1e-3);          // the left turn
  EXPECT_NEAR(min_yaw, -30.0 * kDeg, 1e-3);         // the right turn
  EXPECT_NEAR(p.heading(p.duration()), 0.0, 1e-9);  // left then right: heading +x again
  EXPECT_GT(p.duration(), 30.0);
}

TEST(SynthDrivePath, MotionIsSmoothAndTheCameraLooksAlongTheRoad) {
  const vs::DrivePath p(vs::makeDrivePathConfig("drive"));
  const auto& c = p.config();
  double prev_v = p.speed(0.0), prev_w = p.yawRate(0.0);
  Eigen::Vector3d prev_pos = p.position(0.0);
  for (double t = 0.002; t <= p.duration(); t += 0.002) {
    // No jumps: the speed changes by < 3 m/s^2, the yaw rate by < 1 rad/s^2 (x 2 ms).
    const double v = p.speed(t), w = p.yawRate(t);
    ASSERT_LT(std::abs(v - prev_v), 3.0 * 0.002) << "t " << t;
    ASSERT_LT(std::abs(w - prev_w), 1.0 * 0.002) << "t " << t;
    const Eigen::Vector3d pos = p.position(t);
    ASSERT_LT((pos - prev_pos).norm(), 8.5 * 0.002 * 1.001) << "t " << t;  // 8.5 m/s (and the bobbing)
    prev_v = v;
    prev_w = w;
    prev_pos = pos;
  }
  for (double t = 0.0; t <= p.duration(); t += 0.37) {
    const Eigen::Isometry3d T = p.T_w_c(t);
    // Optical z along the driving direction (up to the pitch wobble), y down (up to the roll).
    const Eigen::Vector3d z = T.linear().col(2), y = T.linear().col(1);
    const double h = p.heading(t);
    EXPECT_LT(std::acos(std::min(1.0, z.head<2>().normalized().dot(Eigen::Vector2d(std::cos(h), std::sin(h))))), 1e-6);
    EXPECT_LE(std::abs(std::asin(z.z())), c.pitch_amp + 1e-9);
    EXPECT_LT(std::acos(std::min(1.0, -y.z())), c.pitch_amp + c.roll_amp + 1e-6);
    EXPECT_NEAR(T.translation().z(), 1.65, c.height_amp + 1e-9);
    EXPECT_TRUE(T.linear().isUnitary(1e-9));
    EXPECT_NEAR(T.linear().determinant(), 1.0, 1e-9);
  }
  // Arc length and its inverse.
  for (double s = 0.0; s <= p.length(); s += 7.7) EXPECT_NEAR(p.arcLength(p.timeAtArcLength(s)), s, 1e-6);
  // Deterministic: two paths from one config agree exactly.
  const vs::DrivePath q(vs::makeDrivePathConfig("drive"));
  EXPECT_EQ((p.T_w_c(12.3).matrix() - q.T_w_c(12.3).matrix()).norm(), 0.0);
}

TEST(SynthDrivePath, RefusesBadConfigs) {
  try {
    vs::makeDrivePathConfig("zigzag");
    FAIL() << "no throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("turn, fast, drive"), std::string::npos) << e.what();
  }
  vs::DrivePathConfig c = vs::makeDrivePathConfig("turn");
  c.legs.clear();
  EXPECT_THROW(vs::DrivePath{c}, std::invalid_argument);
  c = vs::makeDrivePathConfig("turn");
  c.legs[0].length_m = -1.0;
  EXPECT_THROW(vs::DrivePath{c}, std::invalid_argument);
  c = vs::makeDrivePathConfig("turn");
  c.legs[1].ramp_fraction = 0.7;
  EXPECT_THROW(vs::DrivePath{c}, std::invalid_argument);
  c = vs::makeDrivePathConfig("turn");
  c.legs[2].end_speed = 0.0;
  EXPECT_THROW(vs::DrivePath{c}, std::invalid_argument);
  c = vs::makeDrivePathConfig("turn");
  c.legs[0].turn_rad = 0.3;  // a straight that turns
  EXPECT_THROW(vs::DrivePath{c}, std::invalid_argument);
  c = vs::makeDrivePathConfig("turn");
  c.camera_height = std::nan("");
  EXPECT_THROW(vs::DrivePath{c}, std::invalid_argument);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
