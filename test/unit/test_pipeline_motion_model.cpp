// pipeline::MotionModel: the constant-velocity prediction, and how it follows a map rescaled
// about the last pose's centre (ground.enabled's correction).
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

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
