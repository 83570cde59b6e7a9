// Subspace Gauss-Newton BA vs Ceres (Levenberg-Marquardt, SPARSE_SCHUR / DENSE_SCHUR) on
// synthetic problems: batch (10 cameras, perturbed start) and incremental per-frame
// re-optimization in a sliding 10-camera window. Both solvers get the same problem, the same
// Geman-McClure loss, analytic Jacobians (the same formulas) and the same relative cost
// tolerance; costs are reported with baCost (sum of rho in px^2).
//   bench_optimization_ba [--quick] [--no-ceres] [--threads N] [--threads2 M] [--free-cams K] [--frames F]
//                         [--point-iterations P] [--point-extrapolation E] [--point-tolerance T]
// Subspace GN also runs to the tolerance with M threads (default 2; 0 = skip) on the same
// problems, right after the N-thread run: the "*_2threads" / "*_mt" fields.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "cli.h"
#include "vitamin_e/common/timing.h"
#include "vitamin_e/geometry/lie.h"
#include "vitamin_e/geometry/projection.h"
#include "vitamin_e/geometry/triangulation.h"
#include "vitamin_e/optimization/ba_synthetic.h"
#include "vitamin_e/optimization/ba_window.h"
#include "vitamin_e/optimization/subspace_gn.h"

#include "ba_ceres.h"

using namespace vitamin_e;
using namespace vitamin_e::optimization;

namespace {

#ifdef VITAMIN_E_WITH_CERES
using bench::solveCeres;
#endif


struct Args {
  bool quick = false;
  bool no_ceres = false;
  int threads = 1;
  int threads2 = 2;  // second subspace-GN run to the tolerance with this many threads (0: none)
  int free_cams = 3;
  int frames = 5;
  // Per-point refinement after each sweep (BaOptions): 2 Gauss-Newton steps per point, each
  // accepted step doubled up to 8 times while the point's cost decreases, a point stops when a
  // step gains < 1e-4 of its cost.
  int point_iterations = 2;
  int point_extrapolation = 8;
  double point_tolerance = 1e-4;
};

std::vector<bool> freeMask(const BaProblem& p) {
  std::vector<bool> m(p.cameras.size());
  for (size_t c = 0; c < m.size(); ++c) m[c] = !p.cameras[c].fixed;
  return m;
}

struct Result {
  double ms = 0, cpu_ms = 0, cost = 0, err = 0;
  int iters = 0, rejects = 0;
};

struct Row {
  int cams = 0, points = 0, obs = 0, frames = 0;
  Result sgn, sgn_budget, ceres_sparse, ceres_dense;  // sgn_budget: max_sweeps = 5
  Result sgn_mt, sgn_budget_mt;                       // the same with Args::threads2 threads
  double max_cost_diff_mt = 0.0;  // max over frames of |cost(threads2) - cost(threads)| / cost(threads)
  double init_cost = 0, init_err = 0;
  const Result& ceres() const { return ceres_dense.ms < ceres_sparse.ms ? ceres_dense : ceres_sparse; }
};

// Runs both solvers on copies of `start`; accumulates into row (cam error over free cameras).
// Subspace GN runs twice: to the tolerance (max_sweeps 20) and with a per-frame budget of 5.
void solveBoth(const BaProblem& start, const BaProblem& truth, const Args& a, Row* row, BaProblem* sgn_out) {
  const std::vector<bool> mask = freeMask(start);
  BaOptions o;
  o.threads = a.threads;
  o.tolerance = 1e-6;
  o.point_iterations = a.point_iterations;
  o.point_extrapolation = a.point_extrapolation;
  o.point_tolerance = a.point_tolerance;
  BaProblem sgn;
  double cost_1[2] = {0.0, 0.0};
  for (int run = 0; run < (a.threads2 > 0 ? 4 : 2); ++run) {
    const int budget = run % 2;
    const bool mt = run >= 2;
    BaProblem b = start;
    BaOptions ob = o;
    if (budget) ob.max_sweeps = 5;
    if (mt) ob.threads = a.threads2;
    Result& r = mt ? (budget ? row->sgn_budget_mt : row->sgn_mt) : (budget ? row->sgn_budget : row->sgn);
    const auto t0 = TimingClock::now();
    const double c0 = processCpuMs();
    const BaSummary sum = solveSubspaceGaussNewton(b, ob);
    r.ms += elapsedMs(t0);
    r.cpu_ms += processCpuMs() - c0;
    r.iters += sum.sweeps;
    r.rejects += sum.rejected_steps;
    const double cost = baCost(b, o.robust_sigma_px);
    r.cost += cost;
    r.err += cameraPositionRmse(b, truth, mask);
    if (!mt) cost_1[budget] = cost;
    else row->max_cost_diff_mt = std::max(row->max_cost_diff_mt, std::abs(cost - cost_1[budget]) / cost_1[budget]);
    if (!budget && !mt) sgn = b;
  }
  row->init_cost += baCost(start, o.robust_sigma_px);
  row->init_err += cameraPositionRmse(start, truth, mask);
#ifdef VITAMIN_E_WITH_CERES
  for (int dense = 0; dense < 2 && !a.no_ceres; ++dense) {
    BaProblem c = start;
    int it = 0;
    Result& r = dense ? row->ceres_dense : row->ceres_sparse;
    const double c0 = processCpuMs();
    r.ms += solveCeres(c, o.robust_sigma_px, o.tolerance, !dense, a.threads, &it);
    r.cpu_ms += processCpuMs() - c0;
    r.iters += it;
    r.cost += baCost(c, o.robust_sigma_px);
    r.err += cameraPositionRmse(c, truth, mask);
  }
#endif
  if (sgn_out) *sgn_out = sgn;
}

Row runBatch(int points, const Args& a) {
  SyntheticBaConfig cfg;
  cfg.num_cameras = 10;
  cfg.num_points = points;
  cfg.seed = 100 + points;
  const SyntheticBa s = makeSyntheticBa(cfg);
  BaProblem start = s.noisy;
  start.cameras[0].fixed = start.cameras[1].fixed = true;  // gauge
  perturbBaProblem(&start, 0.5, 0.03, 0.05, cfg.seed);
  Row row;
  row.cams = 10;
  row.points = static_cast<int>(start.points.size());
  row.obs = static_cast<int>(start.observations.size());
  row.frames = 1;
  solveBoth(start, s.truth, a, &row, nullptr);
  return row;
}

// Sliding 10-camera window over a sequence; each frame adds one camera (constant-velocity
// initial pose), the points that reach two observations (triangulated from the current
// estimates) and the new observations, then re-optimizes with BaWindowPolicy (newest
// free_cams cameras and their points free, the two oldest of the window fixed).
Row runIncremental(int window_points, const Args& a) {
  const int W = 10, F = a.frames, N = W + F;
  SyntheticBaConfig cfg;
  cfg.num_cameras = N;
  cfg.num_points = static_cast<int>(window_points * (N + 5.5) / (W + 5.5));
  cfg.seed = 7 + window_points;
  const SyntheticBa s = makeSyntheticBa(cfg);
  const BaProblem& obs_src = s.noisy;
  std::vector<Eigen::Isometry3d> est_T(N);
  std::vector<Eigen::Vector3d> est_p(obs_src.points.size());
  std::vector<bool> has_p(obs_src.points.size(), false);
  std::vector<std::vector<int>> obs_of_point(obs_src.points.size());
  for (size_t k = 0; k < obs_src.observations.size(); ++k)
    obs_of_point[obs_src.observations[k].point].push_back(static_cast<int>(k));

  // Builds the window problem [first, last]; new points are triangulated from est_T.
  auto build = [&](int first, int last, BaProblem* prob, BaProblem* truth, std::vector<int>* pt_ids) {
    *prob = BaProblem();
    prob->K = obs_src.K;
    *truth = *prob;
    for (int c = first; c <= last; ++c) {
      prob->cameras.push_back({est_T[c], false});
      truth->cameras.push_back({s.truth.cameras[c].T_w_c, false});
    }
    pt_ids->clear();
    for (size_t p = 0; p < obs_of_point.size(); ++p) {
      std::vector<int> in;
      for (int k : obs_of_point[p]) {
        const int c = obs_src.observations[k].camera;
        if (c >= first && c <= last) in.push_back(k);
      }
      if (in.size() < 2) continue;
      if (!has_p[p]) {
        std::vector<Eigen::Isometry3d> Ts;
        std::vector<Eigen::Vector2d> xy;
        for (int k : in) {
          const BaObservation& o = obs_src.observations[k];
          Ts.push_back(est_T[o.camera]);
          xy.push_back(obs_src.K.unproject(o.uv));
        }
        geometry::TriangulationConfig tc;
        tc.focal_px = obs_src.K.fx;
        tc.min_parallax_deg = 0.3;
        tc.max_reproj_error_px = 5.0;
        const geometry::TriangulationResult tr = geometry::triangulatePoint(Ts, xy, tc);
        if (!tr.ok) continue;
        est_p[p] = tr.p_w;
        has_p[p] = true;
      }
      const int id = static_cast<int>(prob->points.size());
      pt_ids->push_back(static_cast<int>(p));
      prob->points.push_back({est_p[p], false});
      truth->points.push_back({s.truth.points[p].p_w, false});
      for (int k : in) {
        const BaObservation& o = obs_src.observations[k];
        prob->observations.push_back({o.camera - first, id, o.uv});
        truth->observations.push_back(prob->observations.back());
      }
    }
  };
  auto store = [&](const BaProblem& prob, int first, const std::vector<int>& pt_ids) {
    for (size_t c = 0; c < prob.cameras.size(); ++c) est_T[first + c] = prob.cameras[c].T_w_c;
    for (size_t j = 0; j < pt_ids.size(); ++j) est_p[pt_ids[j]] = prob.points[j].p_w;
  };

  // The initial window, converged from the ground truth (two oldest fixed).
  for (int c = 0; c < W; ++c) est_T[c] = s.truth.cameras[c].T_w_c;
  for (size_t p = 0; p < est_p.size(); ++p) {
    est_p[p] = s.truth.points[p].p_w;
    has_p[p] = s.first_camera[p] < W;
  }
  BaProblem prob, truth;
  std::vector<int> pt_ids;
  build(0, W - 1, &prob, &truth, &pt_ids);
  prob.cameras[0].fixed = prob.cameras[1].fixed = true;
  BaOptions tight;
  tight.tolerance = 1e-10;
  tight.max_sweeps = 50;
  solveSubspaceGaussNewton(prob, tight);
  store(prob, 0, pt_ids);

  Row row;
  row.cams = W;
  BaWindowPolicy policy;
  policy.num_free_cameras = a.free_cams;
  for (int f = 0; f < F; ++f) {
    const int n = W + f, first = n - W + 1;
    est_T[n] = est_T[n - 1] * (est_T[n - 2].inverse() * est_T[n - 1]);  // constant velocity
    build(first, n, &prob, &truth, &pt_ids);
    applyBaWindow(selectBaWindow(prob, policy), &prob);
    row.points += static_cast<int>(prob.points.size());
    row.obs += static_cast<int>(prob.observations.size());
    BaProblem out;
    solveBoth(prob, truth, a, &row, &out);
    store(out, first, pt_ids);
  }
  row.frames = F;
  for (Result* r : {&row.sgn, &row.sgn_budget, &row.ceres_sparse, &row.ceres_dense, &row.sgn_mt, &row.sgn_budget_mt}) {
    r->ms /= F;
    r->cpu_ms /= F;
    r->cost /= F;
    r->err /= F;
  }
  row.points /= F;
  row.obs /= F;
  row.init_cost /= F;
  row.init_err /= F;
  return row;
}

void printRow(const char* kind, const Row& r) {
  const Result& c = r.ceres();
  std::printf("%-6s %4d %6d %7d | %9.1f %5.1f %12.2f %9.2e |  (subspace GN, max 5 sweeps)           | %6.2fx %8.5f\n",
              "  sgn5", r.cams, r.points, r.obs, r.sgn_budget.ms, double(r.sgn_budget.iters) / r.frames,
              r.sgn_budget.cost, r.sgn_budget.err, c.ms / r.sgn_budget.ms, r.sgn_budget.cost / c.cost - 1.0);
  std::printf("%-6s %4d %6d %7d | %9.1f %5.1f %12.2f %9.2e | %9.1f %9.1f %4.1f %12.2f %9.2e | %6.2fx %8.5f\n", kind,
              r.cams, r.points, r.obs, r.sgn.ms, double(r.sgn.iters) / r.frames, r.sgn.cost, r.sgn.err,
              r.ceres_sparse.ms, r.ceres_dense.ms, double(c.iters) / r.frames, c.cost, c.err, c.ms / r.sgn.ms,
              r.sgn.cost / c.cost - 1.0);
  if (r.sgn_mt.iters > 0)
    std::printf("%-6s %4d %6d %7d | %9.1f %5.1f %12.2f %9.2e |  (to the tolerance, more threads; max5: %.1f ms) cost "
                "diff %.1e\n",
                " sgnMT", r.cams, r.points, r.obs, r.sgn_mt.ms, double(r.sgn_mt.iters) / r.frames, r.sgn_mt.cost,
                r.sgn_mt.err, r.sgn_budget_mt.ms, r.max_cost_diff_mt);
}

std::string jsonRow(const Row& r, bool batch) {
  const Result& c = r.ceres();
  char buf[1536];
  std::snprintf(buf, sizeof(buf),
                "{%s\"points\":%d,\"sgn_ms\":%.3f,\"ceres_ms\":%.3f,\"sgn_cost\":%.6f,\"ceres_cost\":%.6f,"
                "\"sgn_cam_err\":%.3e,\"ceres_cam_err\":%.3e,\"ceres_sparse_ms\":%.3f,\"ceres_dense_ms\":%.3f,"
                "\"sgn5_ms\":%.3f,\"sgn5_cost\":%.6f,\"sgn5_cam_err\":%.3e,\"init_cost\":%.6f,\"sgn_sweeps\":%.1f,"
                "\"sgn_rejected\":%.1f,\"sgn_cpu_ms\":%.3f,\"ceres_cpu_ms\":%.3f,\"sgn5_cpu_ms\":%.3f,"
                "\"sgn_mt_ms\":%.3f,\"sgn_mt_cpu_ms\":%.3f,\"sgn_mt_cost\":%.6f,\"sgn_mt_sweeps\":%.1f,\"sgn5_mt_ms\":%"
                ".3f,\"sgn_mt_max_cost_rel_diff\":%.3e}",
                batch ? ("\"cams\":" + std::to_string(r.cams) + ",").c_str() : "", r.points, r.sgn.ms, c.ms, r.sgn.cost,
                c.cost, r.sgn.err, c.err, r.ceres_sparse.ms, r.ceres_dense.ms, r.sgn_budget.ms, r.sgn_budget.cost,
                r.sgn_budget.err, r.init_cost, double(r.sgn.iters) / r.frames, double(r.sgn.rejects) / r.frames,
                r.sgn.cpu_ms, c.cpu_ms, r.sgn_budget.cpu_ms, r.sgn_mt.ms, r.sgn_mt.cpu_ms, r.sgn_mt.cost,
                double(r.sgn_mt.iters) / r.frames, r.sgn_budget_mt.ms, r.max_cost_diff_mt);
  return buf;
}

int runAll(const Args& a) {
#ifndef VITAMIN_E_WITH_CERES
  std::fprintf(stderr, "warning: built without Ceres; Ceres columns are zero\n");
#endif
  const std::vector<int> batch_sizes = a.quick ? std::vector<int>{1000} : std::vector<int>{1000, 5000, 20000, 50000};
  const std::vector<int> inc_sizes = a.quick ? std::vector<int>{5000} : std::vector<int>{5000, 20000};
  std::printf("# threads=%d (sgnMT rows and *_mt / *_2threads fields: %d threads), point_iterations=%d, "
              "point_extrapolation=%d, point_tolerance=%g, incremental: free newest "
              "%d cameras of a 10-camera window, %d frames\n",
              a.threads, a.threads2, a.point_iterations, a.point_extrapolation, a.point_tolerance, a.free_cams,
              a.frames);
  std::printf("%-6s %4s %6s %7s | %9s %5s %12s %9s | %9s %9s %4s %12s %9s | %7s %8s\n", "kind", "cams", "points", "obs",
              "sgn_ms", "sweep", "sgn_cost", "sgn_err", "csparse", "cdense", "it", "ceres_cost", "ceres_err", "speedup",
              "cost_rel");
  std::string jb, ji;
  for (int n : batch_sizes) {
    const Row r = runBatch(n, a);
    printRow("batch", r);
    jb += (jb.empty() ? "" : ",") + jsonRow(r, true);
    std::fflush(stdout);
  }
  double ms_per_frame = 0.0, cpu_per_frame = 0.0, ms_budget = 0.0;  // first incremental size
  double ms_mt = 0.0, cpu_mt = 0.0, ms_budget_mt = 0.0, diff_mt = 0.0;
  for (int n : inc_sizes) {
    const Row r = runIncremental(n, a);
    printRow("incr", r);
    ji += (ji.empty() ? "" : ",") + jsonRow(r, false);
    if (n == inc_sizes.front()) {
      ms_per_frame = r.sgn.ms;
      cpu_per_frame = r.sgn.cpu_ms;
      ms_budget = r.sgn_budget.ms;
      ms_mt = r.sgn_mt.ms;
      cpu_mt = r.sgn_mt.cpu_ms;
      ms_budget_mt = r.sgn_budget_mt.ms;
      diff_mt = r.max_cost_diff_mt;
    }
    std::fflush(stdout);
  }
  // incremental_ms_per_frame: subspace GN run to the tolerance (max 20 sweeps), wall clock, on
  // the 5k-point window; the 5-sweep budget is reported separately. *_2threads: the same
  // solves with Args::threads2 threads (the key keeps its name for --threads2 other than 2).
  std::printf("{\"batch\":[%s],\"incremental\":[%s],\"incremental_ms_per_frame\":%.3f,"
              "\"incremental_cpu_ms_per_frame\":%.3f,\"incremental_ms_per_frame_max5_sweeps\":%.3f,"
              "\"threads\":%d,\"threads2\":%d,\"incremental_ms_per_frame_2threads\":%.3f,"
              "\"incremental_cpu_ms_per_frame_2threads\":%.3f,\"incremental_ms_per_frame_max5_sweeps_2threads\":%.3f,"
              "\"incremental_cost_rel_diff_2threads\":%.3e}\n",
              jb.c_str(), ji.c_str(), ms_per_frame, cpu_per_frame, ms_budget, a.threads, a.threads2, ms_mt, cpu_mt,
              ms_budget_mt, diff_mt);
  return 0;
}

}  // namespace

const char* const kUsage =
    "usage: bench_optimization_ba [--quick] [--no-ceres] [--threads N] [--threads2 M] [--free-cams K] [--frames F]\n"
    "                             [--point-iterations P] [--point-extrapolation E] [--point-tolerance T]\n"
    "  --quick               smaller problems\n"
    "  --no-ceres            subspace Gauss-Newton only\n"
    "  --threads N           threads of the first subspace GN run (default 1)\n"
    "  --threads2 M          a second run with M threads (default 2; 0: none)\n"
    "  --free-cams K         incremental: newest cameras free per frame (default 3)\n"
    "  --frames F            incremental: frames (default 5)\n"
    "  --point-iterations P, --point-extrapolation E, --point-tolerance T\n"
    "                        per-point refinement (optimization::BaOptions; default 2, 8, 1e-4)\n";

int main(int argc, char** argv) {
  namespace cli = vitamin_e::cli;
  Args a;
  cli::ArgParser args(argc, argv, kUsage);
  while (args.more()) {
    if (args.flag("--quick", &a.quick) || args.flag("--no-ceres", &a.no_ceres) || args.value("--threads", &a.threads) ||
        args.value("--threads2", &a.threads2) || args.value("--free-cams", &a.free_cams) ||
        args.value("--frames", &a.frames) || args.value("--point-iterations", &a.point_iterations) ||
        args.value("--point-extrapolation", &a.point_extrapolation) ||
        args.value("--point-tolerance", &a.point_tolerance)) {
      continue;
    }
    args.unknown();
  }
  if (a.threads < 1) cli::fail("--threads must be >= 1");
  if (a.threads2 < 0) cli::fail("--threads2 must be >= 0");
  if (a.free_cams < 1 || a.free_cams > 8) cli::fail("--free-cams must be in [1, 8] (a window of 10, 2 fixed)");
  if (a.frames < 1) cli::fail("--frames must be >= 1");
  if (a.point_iterations < 0 || a.point_extrapolation < 0 || a.point_tolerance < 0) {
    cli::fail("--point-iterations, --point-extrapolation and --point-tolerance must be >= 0");
  }
  try {
    return runAll(a);
  } catch (const std::exception& e) {
    cli::fail(e.what());
  }
}
