// The cost of BaOptions::compute_covariance in the per-frame BA's shape: one free camera
// (the newest of 11), the others fixed, 3 sweeps, 0.7 px noise and 2 % outliers, with and
// without the covariance, alternating so that both see the same load.
//   bench_optimization_covariance [--points N] [--runs R]
// Prints the mean wall ms per solve for each and the covariance's own time
// (BaSummary::covariance_ms); the last line is JSON.
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "cli.h"
#include "vitamin_e/common/timing.h"
#include "vitamin_e/optimization/ba_synthetic.h"
#include "vitamin_e/optimization/subspace_gn.h"

using namespace vitamin_e::optimization;

int main(int argc, char** argv) {
  namespace cli = vitamin_e::cli;
  int points = 3000, runs = 100;
  cli::ArgParser args(argc, argv,
                      "usage: bench_optimization_covariance [--points N] [--runs R]\n"
                      "  --points N   points of the per-frame problem (default 3000)\n"
                      "  --runs R     solves with and without the covariance, alternating (default 100)\n");
  while (args.more()) {
    if (args.value("--points", &points) || args.value("--runs", &runs)) continue;
    args.unknown();
  }
  if (points < 10) cli::fail("--points must be >= 10");
  if (runs < 1) cli::fail("--runs must be >= 1");
  SyntheticBaConfig cfg;
  cfg.num_cameras = 11;
  cfg.num_points = points;
  cfg.noise_px = 0.7;
  cfg.outlier_ratio = 0.02;
  cfg.seed = 3;
  const SyntheticBa s = makeSyntheticBa(cfg);
  double ms[2] = {0.0, 0.0}, cov_ms = 0.0;
  int observations = 0;
  for (int r = 0; r < runs; ++r) {
    for (int k = 0; k < 2; ++k) {
      const int on = (r % 2) ? k : 1 - k;  // alternate the order
      BaProblem p = s.noisy;
      for (int c = 0; c + 1 < cfg.num_cameras; ++c) p.cameras[c].fixed = true;
      BaOptions o;
      o.max_sweeps = 3;
      o.compute_covariance = on != 0;
      const auto t0 = vitamin_e::TimingClock::now();
      const BaSummary sum = solveSubspaceGaussNewton(p, o);
      ms[on] += vitamin_e::elapsedMs(t0);
      if (on) cov_ms += sum.covariance_ms;
      observations = sum.active_observations;
    }
  }
  std::printf("per-frame BA, %d points, %d observations, 1 free camera, 3 sweeps, %d runs each:\n", points,
              observations, runs);
  std::printf("  without covariance %.3f ms, with %.3f ms (covariance_ms %.3f)\n", ms[0] / runs, ms[1] / runs,
              cov_ms / runs);
  std::printf("{\"points\":%d,\"observations\":%d,\"ms_off\":%.4f,\"ms_on\":%.4f,\"covariance_ms\":%.4f}\n", points,
              observations, ms[0] / runs, ms[1] / runs, cov_ms / runs);
  return 0;
}
