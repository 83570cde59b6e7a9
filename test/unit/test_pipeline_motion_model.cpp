// pipeline::MotionModel: constant velocity per unit of time, and how it follows a map rescaled
// about the last pose's centre (ground.enabled's correction). Across dropped frames the
// prediction goes as much farther as the gap is longer; at a steady rate (stamps jittering) it
// is exactly one step of the last motion.
#include <gtest/gtest.h>

#include <cmath>

#include "vitamin_e/pipeline/motion_model.h"

using vitamin_e::pipeline::MotionModel;

namespace {

Eigen::Isometry3d pose(double yaw, const Eigen::Vector3d& t) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d(0.2, 1.0, 0.1).normalized()).toRotationMatrix();
  T.translation() = t;
  return T;
}

// A camera on a constant twist: turning about its y axis at 0.2 rad/s while moving along x and z.
Eigen::Isometry3d poseAt(double t) {
  vitamin_e::geometry::Vector6d xi;
  xi << 1.5, 0.0, 0.5, 0.0, 0.2, 0.0;
  return vitamin_e::geometry::expSE3(t * xi);
}
double translationError(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return (a.translation() - b.translation()).norm();
}
double rotationError(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return Eigen::AngleAxisd(a.linear().transpose() * b.linear()).angle();
}
}  // namespace

TEST(MotionModel, PredictsTheLastStepOnceMore) {
  MotionModel m;
  EXPECT_FALSE(m.valid());
  const Eigen::Isometry3d a = pose(0.1, {0.0, 0.0, 0.0});
  const Eigen::Isometry3d b = pose(0.15, {0.3, 0.0, 0.1});
  m.update(a);
  m.update(b);
  EXPECT_TRUE(m.valid());
  const Eigen::Isometry3d expected = b * (a.inverse() * b);
  EXPECT_LT((m.predict().matrix() - expected.matrix()).norm(), 1e-12);
  EXPECT_NEAR(m.lastStepLength(), (a.inverse() * b).translation().norm(), 1e-12);
  // A refined last pose keeps the velocity.
  const Eigen::Isometry3d b2 = pose(0.16, {0.31, 0.0, 0.1});
  m.correctLast(b2);
  EXPECT_LT((m.predict().matrix() - (b2 * (a.inverse() * b)).matrix()).norm(), 1e-12);
}

TEST(MotionModel, ARescaleAboutTheLastCentreScalesThePredictedStep) {
  MotionModel m;
  const Eigen::Isometry3d a = pose(0.1, {1.0, 2.0, 0.5});
  const Eigen::Isometry3d b = pose(0.3, {1.4, 2.1, 0.6});
  m.update(a);
  m.update(b);
  const Eigen::Isometry3d before = m.predict();
  const double step = m.lastStepLength();
  const double factor = 0.8;
  m.rescale(factor);
  // The map moved to centre + factor (x - centre) about the last pose's centre,
  // which stays: the prediction is the old one rescaled the same way.
  const Eigen::Vector3d centre = b.translation();
  EXPECT_LT((m.lastPose().matrix() - b.matrix()).norm(), 1e-15);
  EXPECT_LT((m.predict().translation() - (centre + factor * (before.translation() - centre))).norm(), 1e-12);
  EXPECT_LT((m.predict().linear() - before.linear()).norm(), 1e-12) << "a rescale does not turn the prediction";
  EXPECT_NEAR(m.lastStepLength(), factor * step, 1e-12);
}

TEST(MotionModel, RestartSetsPoseAndVelocity) {
  MotionModel m;
  const Eigen::Isometry3d T = pose(0.2, {1.0, 0.0, 0.0});
  m.restart(T, Eigen::Isometry3d::Identity());
  EXPECT_TRUE(m.valid());
  EXPECT_LT((m.predict().matrix() - T.matrix()).norm(), 1e-15) << "no velocity: the prediction is the pose";
  m.invalidate();
  EXPECT_FALSE(m.valid());
}

TEST(MotionModel, SteadyRateIsOneStepOfTheLastMotion) {
  MotionModel m;
  m.update(poseAt(0.0), 0.0);
  m.update(poseAt(0.05), 0.05);
  // Stamps 10 % late or early are a steady rate: exactly predict().
  for (double t : {0.1, 0.105, 0.095}) {
    EXPECT_EQ(m.stepRatio(t), 1.0) << t;
    EXPECT_TRUE(m.predict(t).isApprox(m.predict(), 0.0)) << t;
  }
  EXPECT_LT(translationError(m.predict(0.1), poseAt(0.1)), 1e-9);
}

TEST(MotionModel, PredictsAcrossSkippedFrames) {
  MotionModel m;
  m.update(poseAt(0.0), 0.0);
  m.update(poseAt(0.05), 0.05);
  for (int skipped : {1, 2}) {
    const double t = 0.05 + 0.05 * (skipped + 1);
    EXPECT_DOUBLE_EQ(m.stepRatio(t), skipped + 1.0);
    // Constant twist: the scaled motion is exact on this path.
    EXPECT_LT(translationError(m.predict(t), poseAt(t)), 1e-9) << skipped;
    EXPECT_LT(rotationError(m.predict(t), poseAt(t)), 1e-9) << skipped;
    // One step would fall short by the skipped frames' motion.
    EXPECT_GT(translationError(m.predict(), poseAt(t)), 0.07 * skipped) << skipped;
  }
  // After the gap, the next frame at the camera's rate: half the step just made.
  m.update(poseAt(0.15), 0.15);
  EXPECT_DOUBLE_EQ(m.stepRatio(0.2), 0.5);
  EXPECT_LT(translationError(m.predict(0.2), poseAt(0.2)), 1e-9);
}

TEST(MotionModel, UnknownTimesCountInFrames) {
  MotionModel m;
  m.update(poseAt(0.0));
  m.update(poseAt(0.05));
  EXPECT_EQ(m.stepRatio(1.0), 1.0);
  EXPECT_TRUE(m.predict(1.0).isApprox(m.predict(), 0.0));
  // restart() without an interval: one step, whatever the gap.
  m.restart(poseAt(0.05), poseAt(0.0).inverse() * poseAt(0.05), 0.05);
  EXPECT_EQ(m.stepRatio(0.15), 1.0);
  m.restart(poseAt(0.05), poseAt(0.0).inverse() * poseAt(0.05), 0.05, 0.05);
  EXPECT_DOUBLE_EQ(m.stepRatio(0.15), 2.0);
  EXPECT_LT(translationError(m.predict(0.15), poseAt(0.15)), 1e-9);
  // A stamp that does not follow the last one: no scaling.
  EXPECT_EQ(m.stepRatio(0.05), 1.0);
  EXPECT_EQ(m.stepRatio(std::nan("")), 1.0);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
