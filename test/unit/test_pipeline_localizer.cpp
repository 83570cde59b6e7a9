// The localizer's trust in a pose: a pose that only a minority of the tracked
// map points agree with is refused, unless its step is the one the motion model
// predicted (blur that corrupts many tracks for one frame does not change the
// camera's speed; a wrong minority consensus changes the step several times).
#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "vitamin_e/map/map.h"
#include "vitamin_e/pipeline/frame_context.h"
#include "vitamin_e/pipeline/localizer.h"
#include "vitamin_e/pipeline/system_config.h"

namespace ve = vitamin_e;
using ve::pipeline::FrameContext;
using ve::pipeline::Localizer;
using ve::pipeline::PoseEstimate;
using ve::pipeline::SystemConfig;

namespace {

// A frame at T_w_c observing `n` points 3-8 m in front; a share `bad` of the
// tracks are moved to random places in the image (tracker failures).
struct Scene {
  ve::map::Map map;
  FrameContext frame;
};

Scene makeScene(const Eigen::Isometry3d& T_w_c, int n, double bad, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::uniform_real_distribution<double> depth(3.0, 8.0);
  Scene s;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d xy1(0.6 * u(rng), 0.4 * u(rng), 1.0);
    ve::map::NewLandmark l;
    l.id = static_cast<std::uint64_t>(i) + 1;
    l.p_w = T_w_c * (depth(rng) * xy1);
    s.map.addLandmark(l);
    ve::pipeline::FrameTrack t{};
    t.id = l.id;
    t.xy = xy1.head<2>();
    if (i < static_cast<int>(bad * n)) t.xy = Eigen::Vector2d(0.6 * u(rng), 0.4 * u(rng));
    s.frame.tracks.push_back(t);
  }
  return s;
}

Eigen::Isometry3d forward(double z) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(0.0, 0.0, z);
  return T;
}

}  // namespace

TEST(Localizer, RefusesAPoseMostPointsDisagreeWithWithoutAPrediction) {
  const Localizer localizer{SystemConfig{}};
  const Eigen::Isometry3d T_w_c = forward(1.0);
  const Scene s = makeScene(T_w_c, 300, 0.6, 1);
  const PoseEstimate e = localizer.estimate(s.frame, s.map, forward(0.9));
  EXPECT_FALSE(e.ok);
  EXPECT_FALSE(e.weak_kept);
  EXPECT_NE(e.why.find("weak pose"), std::string::npos) << e.why;
}

TEST(Localizer, KeepsAWeakPoseThatMovesAsPredicted) {
  const Localizer localizer{SystemConfig{}};
  const Eigen::Isometry3d T_w_last = forward(0.9);
  const Eigen::Isometry3d T_w_predicted = forward(1.02);  // 0.12 predicted, 0.10 true
  const Scene s = makeScene(forward(1.0), 300, 0.6, 2);
  const PoseEstimate e = localizer.estimate(s.frame, s.map, T_w_predicted, &T_w_last);
  ASSERT_TRUE(e.ok) << e.why;
  EXPECT_TRUE(e.weak_kept);
  EXPECT_LT(e.num_inliers, 150);
  EXPECT_NEAR(e.T_w_c.translation().z(), 1.0, 1e-3);
}

TEST(Localizer, RefusesAWeakPoseWhoseStepIsFarFromThePredictedOne) {
  const Localizer localizer{SystemConfig{}};
  const Scene s = makeScene(forward(1.0), 300, 0.6, 3);
  // The camera was predicted to move 0.5 but the pose moved 0.1: a scale jump.
  const Eigen::Isometry3d T_w_last = forward(0.9);
  const Eigen::Isometry3d T_w_predicted = forward(1.4);
  const PoseEstimate e = localizer.estimate(s.frame, s.map, T_w_predicted, &T_w_last);
  EXPECT_FALSE(e.ok);
  EXPECT_FALSE(e.weak_kept);
  // ... and so when the pose moved 4 times the predicted step.
  const Eigen::Isometry3d T_w_last_near = forward(0.98);
  const PoseEstimate e2 = localizer.estimate(s.frame, s.map, forward(0.985), &T_w_last_near);
  EXPECT_FALSE(e2.ok) << "a 0.02 step kept against a 0.005 prediction";
}

TEST(Localizer, AStrongPoseNeedsNoPrediction) {
  const Localizer localizer{SystemConfig{}};
  const Scene s = makeScene(forward(1.0), 300, 0.2, 4);
  const Eigen::Isometry3d T_w_last = forward(0.9);
  const PoseEstimate e = localizer.estimate(s.frame, s.map, forward(1.4), &T_w_last);
  ASSERT_TRUE(e.ok) << e.why;
  EXPECT_FALSE(e.weak_kept);
  EXPECT_NEAR(e.T_w_c.translation().z(), 1.0, 1e-3);
}

TEST(Localizer, WeakPosesAreNeverKeptWithRatioOne) {
  SystemConfig config;
  config.weak_pose_max_step_ratio = 1.0;
  const Localizer localizer{config};
  const Scene s = makeScene(forward(1.0), 300, 0.6, 5);
  const Eigen::Isometry3d T_w_last = forward(0.9);
  const PoseEstimate e = localizer.estimate(s.frame, s.map, forward(1.0), &T_w_last);
  EXPECT_FALSE(e.ok);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
