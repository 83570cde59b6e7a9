// The odometry's step covariance (pipeline::stepCovariance, from the per-frame BA's
// covariance of the frame's own measurements) against the true error of each frame-to-frame
// step on a render with exact ground truth: the normalized estimation error squared (NEES) of
// the steps. eval::stepConsistency is checked on made-up steps first (a covariance that is right
// by construction gives NEES 6; half or twice it is caught).
#include <gtest/gtest.h>

#include <cstdio>
#include <random>

#include "vitamin_e/eval/step_consistency.h"
#include "vitamin_e/geometry/lie.h"
#include "vitamin_e/pipeline/step_covariance.h"
#include "vitamin_e/pipeline/system.h"
#include "vitamin_e/synth/camera_path.h"
#include "vitamin_e/synth/renderer.h"
#include "vitamin_e/synth/scene.h"
#include "vitamin_e/synth/sequence.h"

namespace ve = vitamin_e;
namespace eval = vitamin_e::eval;
namespace geo = vitamin_e::geometry;

namespace {

// Steps drawn from a known covariance (diagonal: 1 mm and 0.1 degree), the estimate at half
// the true scale (a monocular map's units): NEES 6 when the reported covariance is the true one.
double neesOfMadeUpSteps(double reported_over_true) {
  std::mt19937 rng(3);
  std::normal_distribution<double> n(0.0, 1.0);
  const double sp = 1e-3, sr = 1.7e-3;
  eval::Matrix6d C = eval::Matrix6d::Zero();
  C.diagonal() << sp * sp, sp * sp, sp * sp, sr * sr, sr * sr, sr * sr;
  eval::Trajectory truth;
  std::vector<eval::StepEstimate> est;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity(), E = Eigen::Isometry3d::Identity();
  for (int k = 0; k < 400; ++k) {
    geo::Vector6d step;
    step << 0.05, 0.01 * std::sin(0.1 * k), 0.0, 0.0, 0.01, 0.002;
    const Eigen::Isometry3d S = geo::expSE3(step);
    T = T * S;
    Eigen::Isometry3d S_map = S;
    S_map.translation() *= 0.5;  // map units: half a metre
    geo::Vector6d e;
    for (int i = 0; i < 6; ++i) e[i] = n(rng) * std::sqrt(C(i, i));
    E = E * S_map * geo::expSE3(e);
    truth.push_back({0.05 * k, T});
    eval::StepEstimate s;
    s.t = 0.05 * k;
    s.T_w_c = E;
    s.step_covariance = reported_over_true * C;
    s.has_covariance = k > 0;
    est.push_back(s);
  }
  const eval::StepConsistency c = eval::stepConsistency(est, truth);
  EXPECT_EQ(c.steps, 399);
  return c.mean_nees;
}

}  // namespace

TEST(SystemStepCovariance, ConsistencyMeasureOnKnownSteps) {
  EXPECT_NEAR(neesOfMadeUpSteps(1.0), 6.0, 0.6);
  EXPECT_NEAR(neesOfMadeUpSteps(0.5), 12.0, 1.2);
  EXPECT_NEAR(neesOfMadeUpSteps(2.0), 3.0, 0.3);
  // The bounds of the mean of 399 chi-square(6) draws (95 %): about 6 -+ 0.34.
  EXPECT_NEAR(eval::chiSquareQuantile(0.975, 6.0 * 399) / 399, 6.34, 0.02);
  EXPECT_NEAR(eval::chiSquareQuantile(0.025, 6.0 * 399) / 399, 5.67, 0.02);
  EXPECT_NEAR(eval::chiSquareQuantile(0.95, 6.0), 12.59, 0.1);
}

// The room render of the project's generator (160 frames, 752 x 480, its own seed): the mean
// NEES of the steps with the covariance the odometry publishes. The model is fitted on the
// EuRoC V1_01 render (NEES 6 there); on this cleaner render the errors are smaller, so the
// covariance may be conservative, but by no more than 1.5x (NEES >= the lower chi-square bound
// / 1.5), and it must not be overconfident (NEES <= the upper bound).
TEST(SystemStepCovariance, ConsistentOnARender) {
  ve::synth::SequenceConfig seq;
  seq.frames = 160;
  seq.seed = 4;
  const ve::camera::Camera camera = ve::synth::makeSequenceCamera(seq.width, seq.height, true);
  const ve::synth::CameraPath path(ve::synth::makeSequencePath(seq));
  const ve::synth::Scene scene = ve::synth::makeSequenceScene(seq, path);
  const ve::synth::Renderer renderer(scene, camera);
  ve::pipeline::System system(ve::pipeline::SystemConfig{}, camera);
  eval::Trajectory truth;
  std::vector<eval::StepEstimate> steps;
  for (int i = 0; i < seq.frames; ++i) {
    const double t = static_cast<double>(ve::synth::frameTimestampNs(seq, i)) * 1e-9;
    ve::synth::RenderOptions options;
    options.noise_sigma = seq.noise_sigma;
    options.noise_seed = seq.seed * 100000 + static_cast<std::uint64_t>(i);
    const Eigen::Isometry3d T_w_c = path.T_w_c(i / seq.rate_hz);
    truth.push_back({t, T_w_c});
    const ve::pipeline::FrameResult r = system.process(renderer.render(T_w_c, options), t);
    if (!r.pose_valid) continue;
    eval::StepEstimate s;
    s.t = t;
    s.T_w_c = r.T_w_c;
    s.has_covariance = ve::pipeline::stepCovariance(r, &s.step_covariance);
    steps.push_back(s);
  }
  const eval::StepConsistency c = eval::stepConsistency(steps, truth);
  std::printf("%d steps: mean NEES %.3f (chi-square bounds of the mean [%.3f, %.3f]), position %.3f, rotation %.3f, "
              "median %.3f, %.1f %% below the 95 %% point\n",
              c.steps, c.mean_nees, c.lower, c.upper, c.mean_nees_position, c.mean_nees_rotation, c.median_nees,
              100.0 * c.fraction_within_95);
  RecordProperty("mean_nees", std::to_string(c.mean_nees));
  ASSERT_GT(c.steps, 120);
  EXPECT_LE(c.mean_nees, c.upper) << "the step covariance is too small: an EKF would trust the camera too much";
  EXPECT_GE(c.mean_nees, c.lower / 1.5) << "the step covariance is more than 1.5x too large";
  EXPECT_GE(c.fraction_within_95, 0.85);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
