// pipeline::GroundScale: a map whose scale drifts is held to the height of its
// first keyframes above the road that agree; noise within the tolerance, planes
// that are not the road for a few keyframes and fast frames change nothing.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "vitamin_e/pipeline/ground_scale.h"

using vitamin_e::pipeline::GroundScale;
using vitamin_e::pipeline::GroundScaleConfig;
using vitamin_e::pipeline::ScaleCorrection;

namespace {

// Road points `height` below a level camera (camera frame, y down), with facade points.
std::vector<Eigen::Vector3d> roadAt(double height, int seed = 1) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Eigen::Vector3d> pts;
  pts.reserve(500);
  for (int i = 0; i < 300; ++i) pts.push_back({height * (8.0 * u(rng) - 4.0), height, height * (2.0 + 8.0 * u(rng))});
  for (int i = 0; i < 200; ++i)
    pts.push_back({height * (i % 2 ? 5.0 : -5.0), height * (1.0 - 5.0 * u(rng)), height * (2.0 + 20.0 * u(rng))});
  return pts;
}

GroundScaleConfig enabled() {
  GroundScaleConfig c;
  c.enabled = true;
  return c;
}

}  // namespace

TEST(GroundScale, DriftingMapIsHeldToItsFirstHeight) {
  // The map's scale grows 1.5 % per keyframe (a turn); the camera is 1.65 m high.
  GroundScale ground(enabled());
  double map_scale = 1.0;  // map units per metre
  double worst = 0.0;
  for (int k = 0; k < 60; ++k) {
    const ScaleCorrection c = ground.update(roadAt(1.65 * map_scale, k), 0.1 * map_scale);
    ASSERT_TRUE(c.measured) << k;
    EXPECT_NEAR(c.height, 1.65 * map_scale, 0.01 * 1.65 * map_scale) << k;
    map_scale *= c.factor;  // the system rescales the map
    if (k >= 3) worst = std::max(worst, std::abs(map_scale - 1.0));
    map_scale *= 1.015;  // the drift until the next keyframe
  }
  // Without the correction the scale would be 1.015^60 = 2.4 x. Held, it stays within
  // the tolerance, plus the drift the gain leaves each keyframe (drift / gain) and the
  // drift of the keyframes the median lags behind (about a window).
  const GroundScaleConfig c = enabled();
  const double bound = c.tolerance + 0.015 * (1.0 / c.gain + c.window);
  EXPECT_LT(worst, bound);
  EXPECT_NEAR(map_scale, 1.0, bound);
}

TEST(GroundScale, NoiseWithinTheToleranceChangesNothing) {
  GroundScale ground(enabled());
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> noise(-0.015, 0.015);  // reference and median differ by < 0.05
  for (int k = 0; k < 50; ++k) {
    const ScaleCorrection c = ground.update(roadAt(2.0 * (1.0 + noise(rng)), k), 0.1);
    EXPECT_TRUE(c.measured);
    EXPECT_EQ(c.factor, 1.0) << k;
  }
}

// Heights that disagree among themselves (a plane that caught a kerb or a car for a few
// keyframes) correct only when their median is off by more than the tolerance plus
// spread_factor x their spread; the same median from heights that agree corrects.
TEST(GroundScale, ScatteredHeightsMustBeFurtherOffToCorrect) {
  const auto last_factor = [](const std::vector<double>& heights, double spread_factor) {
    GroundScaleConfig config = enabled();
    config.spread_factor = spread_factor;
    GroundScale ground(config);
    for (int k = 0; k < 3; ++k) ground.update(roadAt(1.0, k), 0.1);  // the reference height: 1.0
    ScaleCorrection c;
    for (int k = 0; k < static_cast<int>(heights.size()); ++k) c = ground.update(roadAt(heights[k], 10 + k), 0.1);
    EXPECT_TRUE(c.measured);
    return c.factor;
  };
  // Both windows' median is 0.94: 6.4 % off, beyond the 5 % tolerance.
  const std::vector<double> agreeing = {0.94, 0.94, 0.94, 0.94, 0.94};
  const std::vector<double> scattered = {0.98, 0.90, 0.94, 0.98, 0.90};  // spread 4.3 %: 7.1 % allowed
  EXPECT_GT(last_factor(agreeing, 0.5), 1.0);
  EXPECT_EQ(last_factor(scattered, 0.5), 1.0);
  EXPECT_GT(last_factor(scattered, 0.0), 1.0) << "a fixed tolerance corrects them";
}

// The map's scale grows 12 % per keyframe just after the reference was taken (a turn): every
// height is then off the last accepted one by more than max_change. A window of heights that
// agree among themselves is the map's scale, not a kerb: the correction starts from them instead
// of ignoring the road for the rest of the run.
TEST(GroundScale, ScaleThatMovedPastTheGateIsStillCorrected) {
  GroundScale ground(enabled());
  double map_scale = 1.0;
  for (int k = 0; k < 3; ++k) ground.update(roadAt(1.65, k), 0.1);
  const std::vector<double> jumps = {1.12, 1.03, 1.03, 1.0};  // 1.12 x: past the 10 % gate
  for (double jump : jumps) {
    map_scale *= jump;
    EXPECT_EQ(ground.update(roadAt(1.65 * map_scale, 10), 0.1 * map_scale).factor, 1.0);
  }
  double first_factor = 1.0;
  for (int k = 0; k < 40; ++k) {
    const ScaleCorrection c = ground.update(roadAt(1.65 * map_scale, 20 + k), 0.1 * map_scale);
    ASSERT_TRUE(c.measured) << k;
    if (first_factor == 1.0) first_factor = c.factor;
    map_scale *= c.factor;
  }
  EXPECT_LT(first_factor, 1.0) << "the fifth height off the gate starts the correction";
  const GroundScaleConfig c = enabled();
  EXPECT_NEAR(map_scale, 1.0, c.tolerance + 0.01);
}

TEST(GroundScale, ReferenceIsTheMedianOfTheFirstKeyframes) {
  GroundScale ground(enabled());
  EXPECT_EQ(ground.update(roadAt(1.05), 0.1).reference, 0.0);
  EXPECT_EQ(ground.update(roadAt(1.15), 0.1).reference, 0.0);
  const ScaleCorrection c = ground.update(roadAt(1.1), 0.1);
  EXPECT_NEAR(c.reference, 1.1, 0.01);
  EXPECT_EQ(c.factor, 1.0);
}

// The map's scale halves in a turn at the start (KITTI 07 from its frame 30): the reference
// waits for the first keyframes whose heights agree (within max_change of their median), so the
// map is not pulled back to a scale it had for a moment.
TEST(GroundScale, ReferenceWaitsForHeightsThatAgree) {
  GroundScale ground(enabled());
  const std::vector<double> turning = {1.8, 1.5, 1.25, 1.07, 0.98, 0.88};
  for (double h : turning) EXPECT_EQ(ground.update(roadAt(h), 0.1).reference, 0.0) << h;
  EXPECT_EQ(ground.update(roadAt(0.877), 0.1).reference, 0.0);
  const ScaleCorrection c = ground.update(roadAt(0.873), 0.1);
  EXPECT_NEAR(c.reference, 0.877, 0.01);
  for (int k = 0; k < 10; ++k) EXPECT_EQ(ground.update(roadAt(0.88, k), 0.1).factor, 1.0) << k;
}

TEST(GroundScale, OtherPlanesFastFramesAndNoRoadAreIgnored) {
  GroundScale ground(enabled());
  for (int k = 0; k < 3; ++k) ground.update(roadAt(1.0, k), 0.1);
  // A plane 30 % off the map's height (a car roof, a kerb) is not the road, for fewer keyframes
  // than a window, and again after a road height between them.
  const int window = enabled().window;
  for (int round = 0; round < 3; ++round) {
    for (int k = 0; k + 1 < window; ++k) EXPECT_EQ(ground.update(roadAt(0.7, k), 0.1).factor, 1.0);
    EXPECT_EQ(ground.update(roadAt(1.0, round), 0.1).factor, 1.0);
  }
  // Moving more than max_step_height_ratio x the height per frame: no measurement.
  const ScaleCorrection fast = ground.update(roadAt(1.08), 0.9);
  EXPECT_FALSE(fast.measured);
  EXPECT_EQ(fast.factor, 1.0);
  // Facades only.
  std::vector<Eigen::Vector3d> walls;
  for (const auto& p : roadAt(1.0)) {
    if (std::abs(p.y() - 1.0) > 1e-9) walls.push_back(p);
  }
  EXPECT_FALSE(ground.update(walls, 0.1).measured);
}

TEST(GroundScale, DisabledOrResetKeepsNoState) {
  GroundScale off{GroundScaleConfig{}};
  const ScaleCorrection c = off.update(roadAt(1.0), 0.1);
  EXPECT_FALSE(c.measured);
  EXPECT_EQ(c.factor, 1.0);

  GroundScale ground(enabled());
  for (int k = 0; k < 6; ++k) ground.update(roadAt(1.0, k), 0.1);
  ground.reset();  // a new map with its own scale: 2.0 is its reference, not a drift
  for (int k = 0; k < 10; ++k) EXPECT_EQ(ground.update(roadAt(2.0, k), 0.1).factor, 1.0) << k;
}

TEST(GroundScale, BadConfigIsRefusedByName) {
  GroundScaleConfig c = enabled();
  c.gain = 0.0;
  EXPECT_THROW(c.validate(), std::invalid_argument);
  c = enabled();
  c.spread_factor = -1.0;
  EXPECT_THROW(c.validate(), std::invalid_argument);
  c = enabled();
  c.window = 0;
  try {
    c.validate();
    FAIL() << "window 0 accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("ground.window"), std::string::npos);
  }
}

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
