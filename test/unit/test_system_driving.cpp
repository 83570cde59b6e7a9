// Driving-like motion end to end: the SLAM on the project's
// street scene driven like KITTI 07 (driving_clip.h, 10 Hz).
//   turn: 10 m straight slowing from 3 to 2 m/s, a 90-degree left turn at an
//         intersection at walking speed (up to 3 degrees and 0.2 m per frame),
//         10 m straight speeding up to 3.5 m/s: 122 frames, 28.4 m, 613x185.
//   fast: 60 m straight accelerating from 5 to 15 m/s, then 45 m at 15 m/s
//         (1.5 m per frame): 99 frames, 103.5 m, 613x185.
//   drive, frames 200-259: the end of an 8.5 m/s straight and the braking
//         before a right turn, past parked cars: 60 frames, 37 m, 1226x370.
//   long, town of seed 1: fast's acceleration, then 240 m at 15 m/s: 229 frames,
//         298.5 m, 613x185; run twice, with kitti.yaml's keyframe retirement
//         (map.retire_least_parallax) and with oldest-first.
// config/kitti.yaml, scaled to the image size. The ATE bounds are 1.5x what the
// system measures on these exact, rectified renders, so that a regression to
// twice the error fails (the drive clip's bound is 2 % of its path: it failed
// with a silent scale jump before the tracks the flow loses were found again).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "driving_clip.h"

namespace ve = vitamin_e;
using ve::pipeline::TrackingState;

namespace {

// Each clip is rendered and run once per process, when a test first needs it.
const ve::test::DrivingClip& clip(const std::string& name) {
  if (name == "turn") {
    static const ve::test::DrivingClip turn = ve::test::renderDrivingClip({"turn"});
    return turn;
  }
  if (name == "fast") {
    static const ve::test::DrivingClip fast = ve::test::renderDrivingClip({"fast"});
    return fast;
  }
  if (name == "long" || name == "long_oldest_first") {
    ve::test::ClipSpec long_straight;
    long_straight.path = "long";
    long_straight.seed = 1;
    static const ve::test::DrivingClip long_clip = ve::test::renderDrivingClip(long_straight);
    return long_clip;
  }
  // Full size: frames 200-259 of drive, the end of its 8.5 m/s straight and
  // the braking towards the right turn, past cars parked 1.5 m away.
  ve::test::ClipSpec past_cars;
  past_cars.path = "drive";
  past_cars.width = 1226;
  past_cars.height = 370;
  past_cars.first = 200;
  past_cars.frames = 60;
  static const ve::test::DrivingClip drive = ve::test::renderDrivingClip(past_cars);
  return drive;
}

const ve::test::DrivingRun& run(const std::string& name) {
  if (name == "turn") {
    static const ve::test::DrivingRun turn = ve::test::runDrivingClip(clip("turn"), ve::test::drivingConfig());
    return turn;
  }
  if (name == "fast") {
    static const ve::test::DrivingRun fast = ve::test::runDrivingClip(clip("fast"), ve::test::drivingConfig());
    return fast;
  }
  if (name == "long") {
    static const ve::test::DrivingRun long_run = ve::test::runDrivingClip(clip("long"), ve::test::drivingConfig());
    return long_run;
  }
  if (name == "long_oldest_first") {
    static const ve::test::DrivingRun oldest_first = [] {
      ve::pipeline::SystemConfig config = ve::test::drivingConfig();
      config.map.retire_least_parallax = false;
      return ve::test::runDrivingClip(clip("long_oldest_first"), config);
    }();
    return oldest_first;
  }
  static const ve::test::DrivingRun drive = ve::test::runDrivingClip(clip("drive"), ve::test::drivingConfig(1.0));
  return drive;
}

// Frames from the first map on that have a pose, and how many there are.
std::pair<int, int> trackedAfterInit(const ve::test::DrivingRun& r) {
  if (r.first_init_frame < 0) return {0, 0};
  int tracked = 0, total = 0;
  for (std::size_t i = static_cast<std::size_t>(r.first_init_frame); i < r.results.size(); ++i, ++total)
    if (r.results[i].state == TrackingState::kTracking) ++tracked;
  return {tracked, total};
}

// Sim(3) ATE over the whole clip (N = every frame for the success rate).
ve::eval::EvalResult evaluate(const std::string& name) {
  ve::eval::EvalConfig config;
  config.frames = clip(name).images.size();
  return ve::eval::evaluate(run(name).estimate, clip(name).ground_truth, config);
}

// One line with what the run gave, for the log (and the issue).
void report(const std::string& name) {
  const auto& r = run(name);
  const auto [tracked, total] = trackedAfterInit(r);
  std::printf(
      "[driving %s] %zu frames, %.1f m: first map at frame %lld, tracked after it %d/%d, re-initializations %d, "
      "SLAM %.1f s\n",
      name.c_str(), clip(name).images.size(), clip(name).path_length_m, r.first_init_frame, tracked, total,
      r.init_retries, r.seconds);
  if (r.estimate.size() >= 3) {
    const auto e = evaluate(name);
    std::printf("[driving %s] Sim(3) ATE rmse %.3f m (%.2f%% of the path), matched %zu/%zu, scale %.3f\n", name.c_str(),
                e.ate.rmse, 100.0 * e.ate.rmse / clip(name).path_length_m, e.matched, e.frames, e.alignment.scale);
  }
}

void expectTracksEveryFrameAfterAnEarlyInit(const std::string& name, long long init_by_frame) {
  const auto& r = run(name);
  report(name);
  ASSERT_GE(r.first_init_frame, 0) << "never initialized";
  EXPECT_LT(r.first_init_frame, init_by_frame) << "no map in the first " << init_by_frame << " frames";
  int lost = 0;
  for (std::size_t i = static_cast<std::size_t>(r.first_init_frame); i < r.results.size(); ++i) {
    if (r.results[i].state != TrackingState::kTracking && ++lost <= 5)
      ADD_FAILURE() << "frame " << i << ": " << ve::pipeline::toString(r.results[i].state) << " "
                    << r.results[i].message;
  }
  EXPECT_EQ(lost, 0) << "frames without a pose after the first map";
  EXPECT_EQ(r.init_retries, 0);
}

// After the one Sim(3), the distance covered in each third of the matched
// frames, estimated over true (scale drift and jumps show here).
std::vector<double> thirdsScale(const std::string& name, const ve::eval::EvalResult& e) {
  const std::size_t n = e.pairs.size();
  const auto& gt = clip(name).ground_truth;
  std::vector<double> ratios;
  for (std::size_t third = 0; third < 3; ++third) {
    const std::size_t a = third * (n - 1) / 3, b = (third + 1) * (n - 1) / 3;
    const double est =
        (e.aligned[e.pairs[b].first].T_w_c.translation() - e.aligned[e.pairs[a].first].T_w_c.translation()).norm();
    const double truth = (gt[e.pairs[b].second].T_w_c.translation() - gt[e.pairs[a].second].T_w_c.translation()).norm();
    ratios.push_back(est / truth);
  }
  std::printf("[driving %s] scale of the thirds %.3f %.3f %.3f\n", name.c_str(), ratios[0], ratios[1], ratios[2]);
  return ratios;
}

// Sim(3) ATE below max_ate_m, and the scale right all along, not only on
// average: each third's scale (thirdsScale) within 10%.
void expectSmallAteAndSteadyScale(const std::string& name, double max_ate_m) {
  report(name);
  ASSERT_GE(run(name).estimate.size(), 3u) << "no trajectory";
  const auto e = evaluate(name);
  EXPECT_LT(e.ate.rmse, max_ate_m);
  EXPECT_GE(e.success_rate, 0.75);
  ASSERT_GE(e.pairs.size(), 9u);
  const std::vector<double> ratios = thirdsScale(name, e);
  for (std::size_t third = 0; third < ratios.size(); ++third) EXPECT_NEAR(ratios[third], 1.0, 0.1) << "third " << third;
}

}  // namespace

TEST(SystemDriving, TurnAtWalkingSpeedTracksEveryFrameWithoutReinitializing) {
  // The map must be built on the straight, before the turn starts (frame ~40).
  expectTracksEveryFrameAfterAnEarlyInit("turn", 30);
}

TEST(SystemDriving, TurnAtWalkingSpeedAteIsSmallAfterSim3Alignment) {
  report("turn");
  ASSERT_GE(run("turn").estimate.size(), 3u) << "no trajectory";
  const auto e = evaluate("turn");
  EXPECT_LT(e.ate.rmse, 0.033);     // measured 2.2 cm over 28.4 m
  EXPECT_GE(e.success_rate, 0.75);  // the map built within the first 30 frames, then every frame
}

TEST(SystemDriving, FastStraightTracksEveryFrameWithoutReinitializing) {
  // At 5-7 m/s, the first 20 frames cover 12 m.
  expectTracksEveryFrameAfterAnEarlyInit("fast", 20);
}

TEST(SystemDriving, FastStraightAteIsSmallAndScaleHoldsAfterSim3Alignment) {
  // Measured 18.8 cm over 103.5 m; the speed triples over the clip.
  expectSmallAteAndSteadyScale("fast", 0.28);
}

// The keyframe retirement rule of kitti.yaml (map.retire_least_parallax: the
// keyframe whose removal costs the newest keyframe's points the least parallax
// leaves a full window) keeps the scale over the long fast straight of this
// town. Measured 1.08 m over 298.5 m, the thirds' scale 1.03, 1.00, 0.97.
TEST(SystemDriving, LongFastStraightKeepsItsScaleWithTheParallaxRetirement) {
  EXPECT_TRUE(ve::test::drivingConfig().map.retire_least_parallax) << "kitti.yaml no longer retires by parallax";
  expectTracksEveryFrameAfterAnEarlyInit("long", 20);
  expectSmallAteAndSteadyScale("long", 2.05);
}

// What the rule did here: the same clip with the oldest keyframe retired first
// tracked every frame, but its scale halved within one frame (166, when most
// tracks ended at once): 11.0 m, the thirds' scale 1.15, 1.11, 0.60. Since the
// tracks the flow loses are tracked again from their map points
// (tracker.retry_from_prior, on by default) they no longer end at once, and
// oldest-first keeps the scale as the rule does: measured 1.42 m, the thirds'
// scale 1.04, 1.00, 0.96.
TEST(SystemDriving, LongFastStraightKeepsItsScaleWithOldestFirstRetirementToo) {
  expectSmallAteAndSteadyScale("long_oldest_first", 2.05);
}

// Failed before the tracks the flow loses were tracked again from their map
// points (tracker.retry_from_prior): every frame was tracked without
// re-initializing, but the scale dropped to 0.46 of what it was within 3
// frames (229-232 of drive, a keyframe that adds about 900 points, braking
// from 7 m/s past a car parked 1.5 m away): 1.57 m over 37 m, the thirds'
// scale 1.18, 1.0, 0.51. Measured now: 0.8 cm, the thirds 1.00, 1.00, 1.00.
TEST(SystemDriving, DriveFastPastParkedCarsKeepsItsScale) {
  expectTracksEveryFrameAfterAnEarlyInit("drive", 10);
  expectSmallAteAndSteadyScale("drive", 0.02 * clip("drive").path_length_m);
}

// The clips themselves (always on): the motion is what the tests above claim.
// ground.enabled (config/kitti.yaml): the road plane the system measures at its
// keyframes is the true one. Scaled to metres by the Sim(3) alignment, the camera
// height is the path's 1.65 m (at half size the median is 1.71 m; 1.67 m at full
// size); a plane from the sidewalk (0.15 m higher, -9 %) or the facades would be
// off by more than the bound.
TEST(SystemDriving, GroundPlaneMeasuresTheTrueCameraHeight) {
  const auto& r = run("turn");
  ASSERT_TRUE(ve::test::drivingConfig().ground.enabled);
  ASSERT_GE(r.estimate.size(), 3u);
  const auto e = evaluate("turn");
  std::vector<double> heights_m;
  for (const auto& f : r.results) {
    if (f.diagnostics.ground_height > 0.0) heights_m.push_back(f.diagnostics.ground_height * e.alignment.scale);
  }
  ASSERT_GE(heights_m.size(), 20u) << "the road was measured at too few keyframes";
  std::sort(heights_m.begin(), heights_m.end());
  const double median = heights_m[heights_m.size() / 2];
  std::printf("[driving turn] camera height above the road %.3f m (median of %zu keyframes; %.3f - %.3f m)\n", median,
              heights_m.size(), heights_m.front(), heights_m.back());
  EXPECT_NEAR(median, ve::synth::DrivePathConfig{}.camera_height, 0.05 * 1.65);
}

// The scale corrections move the map, the relocalization index and the motion
// model together: forced on every keyframe (no tolerance, the whole error at
// once), they leave the turn tracked on every frame, without re-initializing; the ATE
// (measured 15 cm, against 2.2 cm with the default ground settings: the map moves at every
// keyframe) is bounded at 1.5x that.
TEST(SystemDriving, ScaleCorrectionsOnEveryKeyframeKeepTheTurnTracked) {
  ve::pipeline::SystemConfig config = ve::test::drivingConfig();
  config.ground.tolerance = 0.0;
  config.ground.gain = 1.0;
  config.ground.window = 1;
  const ve::test::DrivingRun r = ve::test::runDrivingClip(clip("turn"), config);
  int corrected = 0;
  for (const auto& f : r.results) corrected += f.diagnostics.scale_correction != 1.0;
  EXPECT_GE(corrected, 20);
  EXPECT_EQ(r.init_retries, 0);
  ASSERT_GE(r.first_init_frame, 0);
  EXPECT_EQ(r.frames_tracked_since_init, r.results.size() - static_cast<std::size_t>(r.first_init_frame));
  ve::eval::EvalConfig eval;
  eval.frames = clip("turn").images.size();
  const auto e = ve::eval::evaluate(r.estimate, clip("turn").ground_truth, eval);
  std::printf("[driving turn, corrected every keyframe] %d corrections, Sim(3) ATE %.3f m\n", corrected, e.ate.rmse);
  EXPECT_LT(e.ate.rmse, 0.225);
}

TEST(SystemDriving, ClipsHaveTheClaimedMotion) {
  const auto& turn = clip("turn");
  const auto& fast = clip("fast");
  ASSERT_EQ(turn.images.size(), 122u);
  EXPECT_EQ(turn.images.front().cols, 613);
  EXPECT_EQ(turn.images.front().rows, 185);
  double max_rot_deg = 0.0, max_step = 0.0, min_step = 1e9;
  for (std::size_t i = 1; i < turn.ground_truth.size(); ++i) {
    const Eigen::Isometry3d d = turn.ground_truth[i - 1].T_w_c.inverse() * turn.ground_truth[i].T_w_c;
    max_rot_deg = std::max(max_rot_deg, Eigen::AngleAxisd(d.rotation()).angle() * 180.0 / M_PI);
    max_step = std::max(max_step, d.translation().norm());
    min_step = std::min(min_step, d.translation().norm());
  }
  EXPECT_GT(max_rot_deg, 2.8);
  EXPECT_LT(max_rot_deg, 3.1);
  EXPECT_GE(min_step, 0.19);
  EXPECT_LE(max_step, 0.36);
  double fast_max = 0.0;
  for (std::size_t i = 1; i < fast.ground_truth.size(); ++i)
    fast_max = std::max(
        fast_max, (fast.ground_truth[i].T_w_c.translation() - fast.ground_truth[i - 1].T_w_c.translation()).norm());
  EXPECT_NEAR(fast_max, 1.5, 0.01);  // 15 m/s at 10 Hz
  EXPECT_GT(fast.path_length_m, 100.0);
  const auto& long_straight = clip("long");
  ASSERT_EQ(long_straight.images.size(), 229u);
  EXPECT_NEAR(long_straight.path_length_m, 298.5, 0.1);
  const auto& long_gt = long_straight.ground_truth;
  const Eigen::Vector3d last_step =
      long_gt.back().T_w_c.translation() - long_gt[long_gt.size() - 2].T_w_c.translation();
  EXPECT_NEAR(last_step.norm(), 1.5, 0.01);  // still 15 m/s at the end
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
