// Initialization in front of a plane, end to end on the project's own renders
// (376x240, EuRoC distortion, the halved pixel thresholds of
// test_system_robustness): the camera, 2 m from a textured wall and facing it
// with only 0.15 rad of pitch (nearly nothing but the wall in view), slides 4 m
// sideways at up to 1.3 m/s.
//
// The essential matrix of a planar scene is not unique: besides the true
// motion, a 'twisted' one (moving towards the wall, rotated by a few degrees)
// explains every correspondence, and the five-point RANSAC returns either. At
// scene seed 11 it returned the twisted one: 517 of the 969 correspondences
// triangulated in front of both cameras, the median parallax came out 1.2 deg
// instead of 4.5, and the system tracked every frame from that map without a
// single loss while the error grew to 0.75 m RMSE (1.6 m max) over the trip.
// Since the homography's motions compete with the essential one (two_view.cpp),
// the true motion wins with all 969 points.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "vitamin_e/eval/metrics.h"
#include "vitamin_e/pipeline/system.h"
#include "vitamin_e/synth/renderer.h"
#include "vitamin_e/synth/scene.h"
#include "vitamin_e/synth/sequence.h"
#include "vitamin_e/tracking/dense_tracker.h"
#include "wall_trip.h"

namespace ve = vitamin_e;
using ve::pipeline::TrackingState;

namespace {

constexpr int kWidth = 376;
constexpr int kHeight = 240;
constexpr double kRate = 20.0;
constexpr int kFrames = 100;    // 5 s
constexpr double kTripM = 4.0;  // sideways, cosine profile: from rest, 1.26 m/s at the end

// The camera at time t [s]: the outbound half of test_system_reuse's path with
// its wall turned into nearly the whole view: x from -2 to +2 m at y = 1 m, 2 m
// from the room's +y wall, facing it (yaw pi/2 with a small wobble), pitched
// down 0.15 rad instead of 0.4.
Eigen::Isometry3d cameraPose(double t) { return ve::test::wallTripPose(t, 2.0 * kFrames / kRate, kTripM, -0.15); }

struct WallRun {
  std::vector<ve::pipeline::FrameResult> results;
  ve::eval::Trajectory estimate;
  ve::eval::Trajectory ground_truth;
  int init_retries = 0;
};

WallRun runAlongWall(std::uint64_t scene_seed) {
  ve::synth::SceneConfig scene_config;
  scene_config.seed = scene_seed;
  std::vector<Eigen::Vector3d> path;
  // Boxes stay clear of the whole out-and-back path of test_system_reuse (the same rooms).
  for (int i = 0; i < 2 * kFrames; i += 5) path.push_back(cameraPose(i / kRate).translation());
  const ve::synth::Scene scene = ve::synth::Scene::makeRoom(scene_config, path);
  const ve::camera::Camera camera = ve::synth::makeSequenceCamera(kWidth, kHeight, true);
  const ve::synth::Renderer renderer(scene, camera);

  // The tracker's standalone settings: the seeds below were found (a sweep of seeds 1-12)
  // with their correspondences, on which the five-point RANSAC returns the twisted motion.
  // The SLAM's default tracker gives other correspondences (at seed 3 the essential
  // matrix's motion is then the true one, and the homography path is not needed).
  ve::pipeline::SystemConfig config = ve::test::halfResolutionConfig();
  config.tracker = ve::tracking::TrackerConfig{};
  ve::pipeline::System system(config, camera);

  WallRun run;
  for (int i = 0; i < kFrames; ++i) {
    const double t = 50.0 + i / kRate;
    const Eigen::Isometry3d T_w_c = cameraPose(i / kRate);
    ve::synth::RenderOptions options;
    options.noise_sigma = 1.0;
    options.noise_seed = 4000 + static_cast<std::uint64_t>(i);
    run.results.push_back(system.process(renderer.render(T_w_c, options), t));
    run.ground_truth.push_back({t, T_w_c});
  }
  for (const auto& e : system.trajectory()) run.estimate.push_back({e.timestamp, e.T_w_c});
  run.init_retries = system.initRetries();
  return run;
}

void expectAccurate(std::uint64_t scene_seed) {
  const WallRun run = runAlongWall(scene_seed);
  int first = -1;
  for (std::size_t i = 0; i < run.results.size() && first < 0; ++i) {
    if (run.results[i].pose_valid) first = static_cast<int>(i);
  }
  ASSERT_GE(first, 0) << "never initialized";
  ASSERT_LT(first, 30) << "no initialization within 1.5 s";
  // The homography path ran: its motion replaced the essential matrix's (the
  // twisted one at these seeds). Without it the test could pass by luck of the RANSAC.
  const ve::pipeline::FrameResult& init = run.results[first];
  EXPECT_EQ(init.reason, ve::pipeline::StateReason::kInitialized) << init.message;
  EXPECT_TRUE(init.diagnostics.init_from_homography) << init.message;
  for (std::size_t i = static_cast<std::size_t>(first); i < run.results.size(); ++i) {
    EXPECT_EQ(run.results[i].state, TrackingState::kTracking) << "frame " << i << ": " << run.results[i].message;
  }
  EXPECT_EQ(run.init_retries, 0);
  ve::eval::EvalConfig cfg;
  cfg.frames = kFrames;
  const ve::eval::EvalResult r = ve::eval::evaluate(run.estimate, run.ground_truth, cfg);
  std::printf("[planar wall, scene seed %llu] ATE rmse %.4f cm, max %.4f cm\n",
              static_cast<unsigned long long>(scene_seed), 100.0 * r.ate.rmse, 100.0 * r.ate.max);
  // Measured 0.076 and 0.101 cm RMSE, 0.15 and 0.22 cm max (seeds 11 and 3); with the twisted
  // motion, tens of centimetres. The bounds are 1.5x the larger.
  EXPECT_GE(r.matched, static_cast<std::size_t>(0.8 * kFrames));
  EXPECT_LT(r.ate.rmse, 0.0015) << ve::eval::summary(r, cfg);
  EXPECT_LT(r.ate.max, 0.0034) << ve::eval::summary(r, cfg);
}

}  // namespace

// Scene seed 11: the five-point RANSAC returns the twisted motion.
TEST(SystemPlanarInit, WallSeed11TracksTheTrueMotion) { expectAccurate(11); }

// Scene seed 3: the twisted motion too (found in the sweep of seeds 1-12).
TEST(SystemPlanarInit, WallSeed3TracksTheTrueMotion) { expectAccurate(3); }

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
