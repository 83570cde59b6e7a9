#pragma once
// Trajectory accuracy as in the VITAMIN-E paper: associate by timestamp, align
// the estimate to ground truth with Sim(3) (or SE(3)), then absolute trajectory
// error (RMSE/mean/median/max of position error), success rate (matched poses /
// frames) and translational relative pose error (after the scale alignment).
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "vitamin_e/eval/alignment.h"
#include "vitamin_e/eval/trajectory.h"

namespace vitamin_e::eval {

struct EvalConfig {
  double max_dt = 0.02;      // association tolerance [s]
  bool align_scale = true;   // Sim(3); false: SE(3) (scale-known estimates)
  std::size_t frames = 0;    // N for the success rate; 0: number of estimate poses
  double rpe_delta_s = 1.0;  // time delta of the second RPE [s]
  // Given: this estimate -> ground truth transform is applied as it is instead
  // of fitting one (e.g. the one fitted on an earlier run in the same map).
  std::optional<Sim3> given_alignment;
  void validate() const;  // throws std::invalid_argument naming the key
};

struct ErrorStats {
  double rmse = 0.0, mean = 0.0, median = 0.0, max = 0.0;
  std::size_t count = 0;
};
ErrorStats errorStats(const std::vector<double>& errors);

struct EvalResult {
  std::size_t estimate_poses = 0;
  std::size_t ground_truth_poses = 0;
  std::size_t matched = 0;
  std::size_t frames = 0;
  double success_rate = 0.0;   // matched / frames
  Sim3 alignment;              // estimate -> ground truth
  ErrorStats ate;              // position error after alignment [m]
  double path_length_m = 0.0;  // distance the ground truth travels over the matched poses [m]
  ErrorStats rpe_frame;        // translational RPE over 1 matched frame [m]
  ErrorStats rpe_delta;        // translational RPE over rpe_delta_s [m]
  Association pairs;           // (estimate index, ground-truth index)
  std::vector<double> errors;  // per pair, metres
  Trajectory aligned;          // every estimate pose mapped by alignment
};

// Throws TrajectoryError if fewer than 3 poses associate (the message says how
// many estimate and ground-truth poses there were and their time spans).
EvalResult evaluate(const Trajectory& estimate, const Trajectory& ground_truth, const EvalConfig& config = {});

// One JSON object (one line): ate_rmse_m, ate_mean_m, ate_median_m, ate_max_m,
// ate_path_percent (ATE RMSE / path_length_m), path_length_m,
// matched, frames, success_rate, scale, rpe_trans_rmse_m (1 frame),
// rpe_delta_trans_rmse_m, rpe_delta_s, estimate_poses, ground_truth_poses.
std::string toJson(const EvalResult& result, const EvalConfig& config);
// Several readable lines.
std::string summary(const EvalResult& result, const EvalConfig& config);

}  // namespace vitamin_e::eval
