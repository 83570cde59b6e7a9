// The ROS layer's map frame, gravity window, camera -> IMU rotation check, covariance re-expression and
// diagnostics levels, without a ROS master.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include <diagnostic_msgs/DiagnosticStatus.h>

#include "vitamin_e/TrackingStatus.h"
#include "vitamin_e/geometry/lie.h"
#include "vitamin_e/ros/imu_buffer.h"
#include "vitamin_e/ros/map_frame.h"
#include "vitamin_e/ros/tracking_health.h"

using namespace vitamin_e_ros;
namespace geo = vitamin_e::geometry;

namespace {

Eigen::Isometry3d pose(const Eigen::Vector3d& rotvec, const Eigen::Vector3d& t) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = geo::expSO3(rotvec);
  T.translation() = t;
  return T;
}

double angleDeg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0)) * 180.0 / M_PI;
}

}  // namespace

TEST(RosMapFrame, UpHeadingAndCameraAxes) {
  // A camera in a z-up world, pitched down by 20 deg and rolled by 5: its world is the first
  // camera (the SLAM's w), so the true up in w is R_c_world * e_z.
  const Eigen::Matrix3d R_world_c = (Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()) *
                                     Eigen::AngleAxisd(-M_PI / 2 - 0.35, Eigen::Vector3d::UnitX()) *
                                     Eigen::AngleAxisd(0.09, Eigen::Vector3d::UnitZ()))
                                        .toRotationMatrix();
  const Eigen::Vector3d up_w = R_world_c.transpose() * Eigen::Vector3d::UnitZ();
  const Eigen::Isometry3d T_w_c0 = Eigen::Isometry3d::Identity();
  const Eigen::Isometry3d T_map_w = mapFromUp(up_w, T_w_c0);
  EXPECT_TRUE((T_map_w.linear() * T_map_w.linear().transpose()).isIdentity(1e-12));
  EXPECT_NEAR(T_map_w.linear().determinant(), 1.0, 1e-12);
  EXPECT_LT(angleDeg(T_map_w.linear() * up_w, Eigen::Vector3d::UnitZ()), 1e-9);
  // x = the viewing direction made horizontal: the camera's z in the map has no y component.
  const Eigen::Vector3d view_map = T_map_w.linear() * Eigen::Vector3d::UnitZ();
  EXPECT_NEAR(view_map.y(), 0.0, 1e-12);
  EXPECT_GT(view_map.x(), 0.0);
  EXPECT_LT(view_map.z(), 0.0);                                    // pitched down
  EXPECT_TRUE((T_map_w * Eigen::Vector3d::Zero()).isZero(1e-12));  // origin at the first camera
  // Looking straight down: the heading comes from the camera's up instead of a 0/0.
  const Eigen::Isometry3d down = mapFromUp(Eigen::Vector3d(0, 0, -1), T_w_c0);
  EXPECT_TRUE(down.matrix().allFinite());
  EXPECT_LT(angleDeg(down.linear() * Eigen::Vector3d(0, 0, -1), Eigen::Vector3d::UnitZ()), 1e-9);

  // ROS axes: x = optical z, y = -optical x, z = -optical y.
  const Eigen::Isometry3d T_c0 = pose(Eigen::Vector3d(0.1, -0.2, 0.3), Eigen::Vector3d(1, 2, 3));
  const Eigen::Isometry3d axes = mapFromCameraAxes(T_c0);
  const Eigen::Matrix3d R_map_c0 = axes.linear() * T_c0.linear();
  EXPECT_TRUE(R_map_c0.col(2).isApprox(Eigen::Vector3d::UnitX(), 1e-12));
  EXPECT_TRUE(R_map_c0.col(0).isApprox(-Eigen::Vector3d::UnitY(), 1e-12));
  EXPECT_TRUE(R_map_c0.col(1).isApprox(-Eigen::Vector3d::UnitZ(), 1e-12));
  EXPECT_TRUE((axes * T_c0.translation()).isZero(1e-12));

  // Base: the map is the base when the first camera was at T_w_c0.
  const Eigen::Isometry3d T_base_cam = pose(Eigen::Vector3d(-1.2, 0.0, -1.2), Eigen::Vector3d(0.2, 0, 0.5));
  const Eigen::Isometry3d T_map_w_b = mapFromBase(T_base_cam, T_c0);
  EXPECT_TRUE((T_map_w_b * T_c0).isApprox(T_base_cam, 1e-12));
}

TEST(RosMapFrame, GravityWindowRotatesEachSampleByItsPose) {
  // The camera turns by 40 deg about its optical axis during the window; an IMU rotated
  // against the camera (R_c_imu) measures gravity + noise. Rotating each sample by its own
  // pose recovers the up direction of the world; one fixed rotation would not.
  const Eigen::Vector3d up_w = Eigen::Vector3d(0.1, -0.95, 0.2).normalized();
  const Eigen::Matrix3d R_c_imu = geo::expSO3(Eigen::Vector3d(0.3, 1.2, -0.4));
  std::vector<vitamin_e::pipeline::TrajectoryEntry> trajectory;
  for (int k = 0; k <= 20; ++k) {
    vitamin_e::pipeline::TrajectoryEntry e;
    e.timestamp = 10.0 + 0.05 * k;
    e.T_w_c.linear() = geo::expSO3(Eigen::Vector3d(0, 0, 0.7 * k / 20.0));
    trajectory.push_back(e);
  }
  GravityWindow window;
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 0.05);
  for (int k = 0; k < 400; ++k) {  // 200 Hz from 9.0 s to 11.0 s
    const double t = 9.0 + 0.005 * k;
    const Eigen::Matrix3d R_w_c = orientationAt(trajectory, t);
    const Eigen::Vector3d f_imu =
        R_c_imu.transpose() * (R_w_c.transpose() * (9.81 * up_w)) + Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
    window.add(t, f_imu);
  }
  window.add(10.5, Eigen::Vector3d(100, 100, 100));  // out of order: ignored
  const auto e = window.upInWorld(
      11.0, 1.0, [&](double t) { return orientationAt(trajectory, t); }, R_c_imu);
  ASSERT_TRUE(e.ok) << e.message;
  EXPECT_GE(e.samples, 199);
  EXPECT_NEAR(e.magnitude, 9.81, 0.05);
  EXPECT_LT(angleDeg(e.up_w, up_w), 0.1);
  const auto fixed = window.upInWorld(
      11.0, 1.0, [&](double) { return trajectory.back().T_w_c.rotation(); }, R_c_imu);
  EXPECT_GT(angleDeg(fixed.up_w, up_w), 2.0) << "the test does not need per-sample rotation";
  // Too few samples: no estimate, a reason.
  const auto none = window.upInWorld(
      5.0, 1.0, [&](double t) { return orientationAt(trajectory, t); }, R_c_imu);
  EXPECT_FALSE(none.ok);
  EXPECT_FALSE(none.message.empty());
  // The clock going back by more than a second (a bag loop) starts the window over.
  window.add(3.0, Eigen::Vector3d(0, 0, 9.81));
  EXPECT_EQ(window.size(), 1u);
  window.dropBefore(4.0);
  EXPECT_EQ(window.size(), 0u);
}

TEST(RosMapFrame, CovarianceInTheParentFrameAndAtTheBase) {
  // Propagate samples of the right perturbation through T_p_c * exp(delta) and compare the
  // spread of position and left rotation error with the formulas.
  const Eigen::Isometry3d T_p_c = pose(Eigen::Vector3d(0.4, -0.7, 1.1), Eigen::Vector3d(0.5, 1.0, -0.2));
  const Eigen::Isometry3d T_c_b = pose(Eigen::Vector3d(0.0, 0.3, 0.0), Eigen::Vector3d(0.1, -0.3, 0.6));
  Eigen::Matrix<double, 6, 6> A = Eigen::Matrix<double, 6, 6>::Random() * 0.01;
  const Matrix6d cov = A * A.transpose() + Matrix6d::Identity() * 1e-6;
  const Eigen::LLT<Matrix6d> llt(cov);
  std::mt19937 rng(5);
  std::normal_distribution<double> n(0.0, 1.0);
  Matrix6d emp_cam = Matrix6d::Zero(), emp_base = Matrix6d::Zero();
  const int N = 20000;
  const Eigen::Isometry3d T_p_b = T_p_c * T_c_b;
  for (int k = 0; k < N; ++k) {
    geo::Vector6d z;
    for (int i = 0; i < 6; ++i) z(i) = n(rng);
    const geo::Vector6d delta = llt.matrixL() * z;
    const Eigen::Isometry3d T = T_p_c * geo::expSE3(delta);
    geo::Vector6d e_cam, e_base;
    e_cam << T.translation() - T_p_c.translation(), geo::logSO3(T.linear() * T_p_c.linear().transpose());
    const Eigen::Isometry3d Tb = T * T_c_b;
    e_base << Tb.translation() - T_p_b.translation(), geo::logSO3(Tb.linear() * T_p_b.linear().transpose());
    emp_cam += e_cam * e_cam.transpose() / N;
    emp_base += e_base * e_base.transpose() / N;
  }
  const Matrix6d in_parent = covarianceInParent(cov, T_p_c.linear());
  const Matrix6d at_base = covarianceMovedTo(in_parent, T_p_c.linear() * T_c_b.translation());
  EXPECT_LT((emp_cam - in_parent).norm(), 0.05 * in_parent.norm()) << emp_cam << "\n\n" << in_parent;
  EXPECT_LT((emp_base - at_base).norm(), 0.05 * at_base.norm()) << emp_base << "\n\n" << at_base;
}

TEST(RosTrackingHealth, Levels) {
  using DS = diagnostic_msgs::DiagnosticStatus;
  HealthInput in;
  EXPECT_EQ(trackingHealth(in).level, DS::ERROR);  // no calibration
  in.calibrated = true;
  EXPECT_EQ(trackingHealth(in).level, DS::WARN);  // no image yet
  in.received = 100;
  in.since_input_s = 0.02;
  in.since_processed_s = 0.03;
  in.input_hz = in.processed_hz = 20.0;
  in.state = vitamin_e::TrackingStatus::TRACKING;
  EXPECT_EQ(trackingHealth(in).level, DS::OK);
  EXPECT_EQ(trackingHealth(in).summary, "tracking");
  in.processed_hz = 10.0;  // half the frames
  const Health slow = trackingHealth(in);
  EXPECT_EQ(slow.level, DS::WARN);
  EXPECT_NE(slow.summary.find("10.0 of 20.0"), std::string::npos) << slow.summary;
  in.processed_hz = 20.0;
  in.state = vitamin_e::TrackingStatus::INITIALIZING;
  EXPECT_EQ(trackingHealth(in).level, DS::WARN);
  in.state = vitamin_e::TrackingStatus::LOST;
  in.message = "only 3 tracked map points";
  EXPECT_EQ(trackingHealth(in).level, DS::ERROR);
  EXPECT_NE(trackingHealth(in).summary.find("only 3"), std::string::npos);
  in.state = vitamin_e::TrackingStatus::TRACKING;
  in.since_processed_s = 5.0;  // images arrive, the SLAM is stuck
  EXPECT_EQ(trackingHealth(in).level, DS::ERROR);
  in.since_input_s = 5.0;  // the camera stopped: a warning, not the SLAM's fault
  EXPECT_EQ(trackingHealth(in).level, DS::WARN);
  // Bag mode, the SLAM stuck on a frame: the full queue holds the callback (no new image seen),
  // but frames wait: the SLAM's fault.
  in.queue_all = true;
  in.queue_capacity = 4;
  in.queued = 4;
  EXPECT_EQ(trackingHealth(in).level, DS::ERROR);
  EXPECT_NE(trackingHealth(in).summary.find("frames wait"), std::string::npos) << trackingHealth(in).summary;
  // ... and processing, but slower than the input: the queue is full, the latency grows.
  in.since_input_s = 0.02;
  in.since_processed_s = 0.03;
  const Health full = trackingHealth(in);
  EXPECT_EQ(full.level, DS::WARN);
  EXPECT_NE(full.summary.find("queue is full"), std::string::npos) << full.summary;
  in.queued = 1;
  EXPECT_EQ(trackingHealth(in).level, DS::OK);
}

// The camera -> IMU rotation check: a camera turning 2 deg per frame about (0.2, 1, 0.1); the
// gyroscope gives its increments through R_c_imu_wrong * R_c_imu_true^-1 (identity: the right
// mounting). The verdict comes once, at the 10th interval (20 deg turned, over the 8 deg and 10
// intervals asked), and only intervals between consecutive frames with a pose count.
namespace {

struct RotationRun {
  std::vector<int> verdict_frames;
  vitamin_e_ros::ImuRotationCheck::Verdict verdict;
};

RotationRun runRotationCheck(const Eigen::Matrix3d& R_mounting_error, const std::vector<int>& frames_without_pose,
                             bool gyro_available = true) {
  vitamin_e_ros::ImuRotationCheck check;
  const Eigen::Vector3d axis = Eigen::Vector3d(0.2, 1.0, 0.1).normalized();
  const double step = 2.0 * M_PI / 180.0;
  RotationRun run;
  for (int k = 0; k < 30; ++k) {
    const double t = 0.1 * k;
    const Eigen::Matrix3d R_w_c = geo::expSO3(axis * step * k);
    const bool pose = std::find(frames_without_pose.begin(), frames_without_pose.end(), k) == frames_without_pose.end();
    const auto gyro = [&](double t0, double t1, Eigen::Vector3d* theta_c) {
      *theta_c = R_mounting_error * axis * step * std::round((t1 - t0) / 0.1);
      return gyro_available;
    };
    if (const auto v = check.add(pose, t, R_w_c, gyro)) {
      run.verdict_frames.push_back(k);
      run.verdict = *v;
    }
  }
  return run;
}

}  // namespace

TEST(RosImuRotationCheck, TheRightMountingAgreesOnceAtTheTenthInterval) {
  const RotationRun run = runRotationCheck(Eigen::Matrix3d::Identity(), {});
  ASSERT_EQ(run.verdict_frames, std::vector<int>{10});
  EXPECT_TRUE(run.verdict.agrees);
  EXPECT_NEAR(run.verdict.mean_angle_deg, 0.0, 1e-3);
  EXPECT_NEAR(run.verdict.rotation_deg, 20.0, 1e-6);
  EXPECT_EQ(run.verdict.intervals, 10);
}

TEST(RosImuRotationCheck, AMountingTurnedByHalfARightAngleIsWrong) {
  const RotationRun run = runRotationCheck(geo::expSO3(Eigen::Vector3d(M_PI / 4, 0.0, 0.0)), {});
  ASSERT_EQ(run.verdict_frames, std::vector<int>{10});
  EXPECT_FALSE(run.verdict.agrees);
  EXPECT_GT(run.verdict.mean_angle_deg, 30.0);
}

TEST(RosImuRotationCheck, NoIntervalAcrossAFrameWithoutAPoseNorWithoutTheGyroscope) {
  // Frames 3 and 4 without a pose: intervals 2-3, 3-4 and 4-5 are lost, the 10th interval ends at 13.
  EXPECT_EQ(runRotationCheck(Eigen::Matrix3d::Identity(), {3, 4}).verdict_frames, std::vector<int>{13});
  EXPECT_TRUE(runRotationCheck(Eigen::Matrix3d::Identity(), {}, false).verdict_frames.empty());
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
