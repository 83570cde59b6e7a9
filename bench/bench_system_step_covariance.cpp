// Consistency of the pose covariance the SLAM reports (FrameResult::T_w_c_covariance, what
// the ROS odometry publishes) with the true error of the frame-to-frame motion: the NEES of
// each step against the ground truth (eval::stepConsistency), its mean against the
// chi-square bounds, on a render with exact ground truth.
//   bench_system_step_covariance [--frames N] [--seed S] [--width W --height H]   the project's room render
//   bench_system_step_covariance --dataset DIR [--ground-truth FILE] [--config YAML] [--max-frames N]
// --dump FILE writes one line per step: t keyframe step(6) error(6) covariance(36, row-major).
// Prints a table, then JSON on its last line.
#include <cstdio>
#include <fstream>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "cli.h"
#include "vitamin_e/eval/step_consistency.h"
#include "vitamin_e/eval/trajectory.h"
#include "vitamin_e/geometry/lie.h"
#include "vitamin_e/io/dataset.h"
#include "vitamin_e/pipeline/step_covariance.h"
#include "vitamin_e/pipeline/system.h"
#include "vitamin_e/synth/camera_path.h"
#include "vitamin_e/synth/renderer.h"
#include "vitamin_e/synth/scene.h"
#include "vitamin_e/synth/sequence.h"

namespace ve = vitamin_e;
namespace cli = vitamin_e::cli;

namespace {

constexpr const char* kUsage =
    "usage: bench_system_step_covariance [--frames N] [--seed S] [--width W --height H]\n"
    "       bench_system_step_covariance --dataset DIR [--ground-truth FILE] [--config YAML] [--max-frames N]\n"
    "  --frames N         synthetic room render: frames (default 200)\n"
    "  --seed S           its scene and noise seed (default 1)\n"
    "  --width/--height   its image size (default 752 x 480)\n"
    "  --speed V          its mean camera speed [m/s] (default 0.4)\n"
    "  --dataset DIR      a EuRoC folder with ground truth instead (e.g. a render of render_sequence.py)\n"
    "  --ground-truth F   T_w_c of the camera (TUM) when the folder's own is the body's (default: the\n"
    "                     folder's groundtruth_cam0_tum.txt, else its body ground truth and T_BS)\n"
    "  --config YAML      SLAM configuration (default: built-in)\n"
    "  --max-frames N     process at most N frames of the dataset\n"
    "  --dump FILE        per step: t keyframe step(6) error(6) covariance(36)\n";

struct Run {
  std::vector<ve::eval::StepEstimate> steps;
  std::vector<int> keyframe;
  ve::eval::Trajectory truth;
  std::size_t frames = 0;
};

void addResult(const ve::pipeline::FrameResult& r, Run* run) {
  ++run->frames;
  if (!r.pose_valid) return;
  ve::eval::StepEstimate e;
  e.t = r.timestamp;
  e.T_w_c = r.T_w_c;
  e.has_covariance = ve::pipeline::stepCovariance(r, &e.step_covariance);
  run->steps.push_back(e);
  run->keyframe.push_back(r.diagnostics.keyframe ? 1 : 0);
}

Run runSynthetic(int frames, std::uint64_t seed, int width, int height, double speed) {
  ve::synth::SequenceConfig seq;
  seq.speed = speed;
  seq.frames = frames;
  seq.seed = seed;
  seq.width = width;
  seq.height = height;
  const ve::camera::Camera camera = ve::synth::makeSequenceCamera(seq.width, seq.height, true);
  const ve::synth::CameraPath path(ve::synth::makeSequencePath(seq));
  const ve::synth::Scene scene = ve::synth::makeSequenceScene(seq, path);
  const ve::synth::Renderer renderer(scene, camera);
  ve::pipeline::System system(ve::pipeline::SystemConfig{}, camera);
  Run run;
  for (int i = 0; i < frames; ++i) {
    const double t = static_cast<double>(ve::synth::frameTimestampNs(seq, i)) * 1e-9;
    ve::synth::RenderOptions options;
    options.noise_sigma = seq.noise_sigma;
    options.noise_seed = seed * 100000 + static_cast<std::uint64_t>(i);
    const Eigen::Isometry3d T_w_c = path.T_w_c(i / seq.rate_hz);
    addResult(system.process(renderer.render(T_w_c, options), t), &run);
    run.truth.push_back({t, T_w_c});
  }
  return run;
}

Run runDataset(const std::string& dir, const std::string& truth_path, const std::string& config_path,
               std::size_t max_frames) {
  const auto dataset = ve::io::openDataset(dir);
  const ve::pipeline::SystemConfig config =
      config_path.empty() ? ve::pipeline::SystemConfig{} : ve::pipeline::loadSystemConfig(config_path);
  ve::pipeline::System system(config, dataset->calibration().camera);
  Run run;
  if (!truth_path.empty()) {
    run.truth = ve::eval::readTrajectory(truth_path);
  } else if (std::ifstream(dir + "/groundtruth_cam0_tum.txt").good()) {
    run.truth = ve::eval::readTum(dir + "/groundtruth_cam0_tum.txt");
  } else {
    const std::string gt = dataset->groundTruthPath();
    if (gt.empty()) cli::fail(dir + " has no ground truth (give --ground-truth)");
    run.truth = ve::eval::applyBodyToCamera(ve::eval::readTrajectory(gt), dataset->calibration().T_b_c);
  }
  const std::size_t n = max_frames > 0 ? std::min(max_frames, dataset->size()) : dataset->size();
  for (std::size_t i = 0; i < n; ++i) addResult(system.process(dataset->loadImage(i), dataset->timestamp(i)), &run);
  return run;
}

}  // namespace

int main(int argc, char** argv) {
  cli::ArgParser args(argc, argv, kUsage);
  int frames = 200, width = 752, height = 480;
  double speed = 0.4;
  std::uint64_t seed = 1;
  std::size_t max_frames = 0;
  std::string dataset, truth, config, dump;
  while (args.more()) {
    if (args.value("--frames", &frames) || args.value("--seed", &seed) || args.value("--width", &width) ||
        args.value("--speed", &speed) || args.value("--height", &height) || args.value("--dataset", &dataset) ||
        args.value("--ground-truth", &truth) || args.value("--config", &config) ||
        args.value("--max-frames", &max_frames) || args.value("--dump", &dump)) {
      continue;
    }
    args.unknown();
  }
  if (frames < 30) cli::fail("--frames must be >= 30");
  Run run;
  try {
    run = dataset.empty() ? runSynthetic(frames, seed, width, height, speed)
                          : runDataset(dataset, truth, config, max_frames);
  } catch (const std::exception& e) {
    cli::fail(e.what());
  }
  ve::eval::StepConsistency c;
  try {
    c = ve::eval::stepConsistency(run.steps, run.truth);
  } catch (const std::exception& e) {
    cli::fail(e.what());
  }
  if (!dump.empty()) {
    // The steps again, with the estimated step, its error and covariance, for a closer look.
    std::ofstream out(dump);
    if (!out) cli::fail("cannot write " + dump);
    std::map<double, std::size_t> error_of;
    for (std::size_t k = 0; k < c.stamps.size(); ++k) error_of[c.stamps[k]] = k;
    for (std::size_t k = 1; k < run.steps.size(); ++k) {
      const auto& a = run.steps[k - 1];
      const auto& b = run.steps[k];
      const auto e = error_of.find(b.t);
      if (!b.has_covariance || e == error_of.end()) continue;
      const ve::geometry::Vector6d xi = ve::geometry::logSE3(a.T_w_c.inverse() * b.T_w_c);
      out << b.t << " " << run.keyframe[k];
      for (int i = 0; i < 6; ++i) out << " " << xi[i];
      for (int i = 0; i < 6; ++i) out << " " << c.errors[e->second][i];
      for (int i = 0; i < 36; ++i) out << " " << b.step_covariance(i / 6, i % 6);
      out << "\n";
    }
  }
  std::printf("frames %zu, poses %zu, steps with covariance and ground truth %d\n", run.frames, run.steps.size(),
              c.steps);
  std::printf("mean NEES %.3f (6 expected; 95 %% bounds of the mean [%.3f, %.3f]) -> %s\n", c.mean_nees, c.lower,
              c.upper, c.consistent() ? "consistent" : (c.mean_nees > c.upper ? "covariance too small" : "too large"));
  std::printf("  position part %.3f, rotation part %.3f (3 expected each); median %.3f (5.35 expected); %.1f %% of "
              "steps below chi2(6) 95 %% (95 expected)\n",
              c.mean_nees_position, c.mean_nees_rotation, c.median_nees, 100.0 * c.fraction_within_95);
  std::printf("{\"frames\": %zu, \"steps\": %d, \"mean_nees\": %.4f, \"lower\": %.4f, \"upper\": %.4f, "
              "\"mean_nees_position\": %.4f, \"mean_nees_rotation\": %.4f, \"median_nees\": %.4f, "
              "\"fraction_within_95\": %.4f, \"consistent\": %s}\n",
              run.frames, c.steps, c.mean_nees, c.lower, c.upper, c.mean_nees_position, c.mean_nees_rotation,
              c.median_nees, c.fraction_within_95, c.consistent() ? "true" : "false");
  return 0;
}
