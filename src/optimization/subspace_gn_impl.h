#pragma once
// Internal to vitamin_e_optimization: the state and steps of the subspace Gauss-Newton solver
// (see include/vitamin_e/optimization/subspace_gn.h for the method). Split in
// subspace_gn.cpp (sweeps, camera and point steps) and subspace_gn_linearize.cpp (problem
// structure, linearization, costs, per-point refinement).
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "vitamin_e/geometry/lie.h"
#include "vitamin_e/geometry/projection.h"
#include "vitamin_e/optimization/block_solvers.h"
#include "vitamin_e/optimization/subspace_gn.h"

namespace vitamin_e {
namespace optimization {
namespace detail {

using geometry::Matrix6d;
using geometry::Vector6d;
using Matrix26d = Eigen::Matrix<double, 2, 6>;
using Matrix23d = Eigen::Matrix<double, 2, 3>;

constexpr double kMinDepth = 1e-9;

// A fixed set of threads for one solve. run(chunks, f) calls f(c) once for every chunk c in
// [0, chunks) on whichever thread claims it first (the caller takes part) and returns when all
// are done: a worker that the OS has not scheduled (the 2 cores are shared with the tracker and
// other processes) only means the caller does more chunks, instead of a barrier waiting for it.
// Results must not depend on who ran a chunk: callers keep per-chunk partial sums and combine
// them in chunk order. The workers are created once (a std::thread costs ~50 us to start and a
// sweep has ~5 parallel loops); between loops they spin for ~kSpinUs, then sleep.
class WorkerPool {
 public:
  explicit WorkerPool(int threads);
  ~WorkerPool();
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;
  int size() const { return n_; }
  template <typename F>
  void run(int chunks, F& f) {
    fn_ = [](void* ctx, int c) { (*static_cast<F*>(ctx))(c); };
    ctx_ = &f;
    dispatch(chunks);
  }

 private:
  // state_: generation (high 32 bits), number of chunks (16 bits), next unclaimed chunk (16 bits).
  void dispatch(int chunks);
  void work(std::uint64_t v);  // claims and runs chunks of the job whose state was v
  void loop();
  int n_;
  void (*fn_)(void*, int) = nullptr;
  void* ctx_ = nullptr;
  std::uint32_t gen_ = 0;  // caller's copy
  std::atomic<std::uint64_t> state_{0};
  std::atomic<int> done_{0};
  std::atomic<int> sleepers_{0};
  std::atomic<bool> stop_{false};
  std::mutex m_;
  std::condition_variable cv_;
  std::vector<std::thread> workers_;
};

// Boundaries b[0] = 0 <= b[1] <= ... <= b[T] = n splitting [0, n) in T contiguous ranges of
// about equal weight; prefix[k] = total weight of items [0, k) (size n + 1).
std::vector<int> weightedSplit(const std::vector<double>& prefix, int T);

class SubspaceGn {
 public:
  SubspaceGn(BaProblem& p, const BaOptions& o);
  int freeCameras() const { return static_cast<int>(cams_.size()); }
  int freePoints() const { return static_cast<int>(pts_.size()); }
  int rejectedSteps() const { return rejected_; }
  int activeObservations() const { return static_cast<int>(pt_obs_.size() + cam_only_obs_.size()); }
  // Runs the sweeps; returns {sweeps, converged, lambda}.
  void run(int* sweeps, bool* converged, double* lambda_out);
  // Cost of all observations before run() changed anything: the constant part (observations
  // with nothing free, summed in buildStructure) plus the first linearization's active cost.
  double initialCost() const { return fixed_cost_ + initial_active_cost_; }
  // After run(): every observation's residual norm (baResidualNorms) and the final cost
  // (baCost), evaluating only the observations that touch a free variable.
  double finish(std::vector<double>* residual_px) const;
  // After run(): BaOptions::compute_covariance (see there), into summary's covariance fields.
  void covariance(BaSummary* summary);

 private:
  void buildStructure();
  // Builds all blocks at the current estimate; returns the robust cost of the active part.
  double linearize();
  // IRLS: each residual's Hessian block is w J^T J and its gradient w J^T r, w = rho'(|r|^2).
  // The second-order term of Geman-McClure (rho'' < 0) is dropped, as Ceres does; using it
  // (floored to stay positive definite) was tried and converged worse on the benchmark.
  // Computes dc_, dp_ for the damping lambda from the current linearization.
  void solveStep(double lambda);
  // Eq. 12 relinearized: Gauss-Newton steps on each point alone with the cameras fixed (each
  // point's cost only involves its own observations, so every step is checked and kept per
  // point). Returns the total cost decrease.
  double refinePoints(int iterations);
  // Robust cost of free point j's observations with the point at x (cameras as cached); with
  // H and g, also the point's IRLS block and gradient there.
  double evalPoint(int j, const Eigen::Vector3d& x, Eigen::Matrix3d* H, Eigen::Vector3d* g) const;
  // Eq. 12: dp_j = -H_pp^-1 (g_p + sum_i H_pc dc_i), independent per point.
  void pointUpdates();
  void cacheCameras();
  void saveState();
  void restoreState();
  void applyStep();
  // Robust cost of the active part at the current estimate. With point_iterations > 0 it also
  // keeps each free point's cost, 3x3 block and gradient (cameras fixed) at this estimate:
  // when the step is accepted they are the first linearization of refinePoints.
  double activeCost();

  // Runs f(begin, end, c) on each chunk c = [split[c], split[c + 1]) of the free points, on the
  // pool's threads (or f(0, n, 0) without a pool). The chunks are fixed per solve and f keeps
  // partial sums per chunk, combined in chunk order: the results do not depend on which thread
  // ran which chunk, and differ from one thread's only by the rounding of those sums.
  template <typename F>
  void forChunks(const std::vector<int>& split, F&& f) {
    if (!pool_) {
      f(0, split.back(), 0);
      return;
    }
    auto g = [&](int c) { f(split[c], split[c + 1], c); };
    pool_->run(static_cast<int>(split.size()) - 1, g);
  }

  BaProblem& P_;
  const BaOptions& O_;
  // Threads used for this solve: 1 below 256 free points per thread (a parallel loop costs a few
  // microseconds of hand-over, more than the work of a small problem).
  int T_ = 1;
  int chunks_ = 1;  // chunks per parallel loop: 1 with one thread, else kChunksPerThread * T_
  std::unique_ptr<WorkerPool> pool_;
  // Chunks of free points, balanced by the observations (linearization, costs, refinement)
  // and by the camera-pair terms of the Schur complement (k(k+1)/2 for k slots).
  std::vector<int> split_obs_, split_schur_;
  geometry::GemanMcClure kernel_;
  camera::Pinhole K_;
  std::vector<int> cam_var_, pt_var_, cams_, pts_;
  std::vector<int> pt_begin_, pt_obs_, obs_slot_, cam_only_obs_;
  // Point-major copies of the active observations (pt_obs_ order): camera index and pixel, so
  // the inner loops read contiguous memory instead of going through P_.observations.
  std::vector<int> obs_cam_;
  std::vector<Eigen::Vector2d> obs_uv_;
  std::vector<int> slot_begin_, slot_cam_, slot_point_, cam_begin_, cam_slots_;
  double fixed_cost_ = 0.0;
  std::vector<double> fixed_norm_;  // residual norm of each observation with nothing free, else -1
  double initial_active_cost_ = 0.0;
  int rejected_ = 0;
  // Hcc_: the camera blocks H_cc; with use_schur only the part from observations of fixed
  // points (the rest enters S through the Schur diagonal blocks). hdiag_: diagonal of the whole
  // H_cc (LM damping).
  std::vector<Matrix6d> Hcc_, Hd_;
  std::vector<Vector6d> hdiag_;
  BlockMatrix6 S_;
  std::vector<Vector6d> gc_, b_, dc_;
  std::vector<Eigen::Matrix3d> Hpp_, Hpp_inv_, R_;
  // Per camera, 12 doubles laid out for 2-wide arithmetic on the two residual rows: the first
  // two columns of R_w_c interleaved, (R00, R01, R10, R11, R20, R21), then its third column
  // (R02, R12, R22) and t_w_c. Row k of [x y]^T = R^T d is then one packed product per d_k.
  std::vector<std::array<double, 12>> cam_pack_;
  std::vector<Eigen::Vector3d> gp_, dp_, t_, saved_pts_;
  std::vector<Eigen::Matrix3d> ref_H_;  // activeCost's per-point blocks for refinePoints
  std::vector<Eigen::Vector3d> ref_g_;
  std::vector<double> ref_c_;
  // Per slot (free camera, free point): the two rows of d r / d camera and the two rows of
  // d r / d point scaled by the IRLS weight, so that H_cp = Jc^T Wjp. Kept as rows (rank 2)
  // instead of the 6x3 product: the Schur complement and the coupling products are cheaper
  // through the 2-dimensional residual space.
  std::vector<Matrix26d> Jc_;
  std::vector<Matrix23d> Wjp_;
  std::vector<double> slot_w_;  // IRLS weight of the slot's observation
  std::vector<Eigen::Isometry3d> saved_cams_;
  std::vector<std::vector<Matrix6d>> Hcc_t_;  // per-chunk camera blocks (upper triangle)
  std::vector<std::vector<Vector6d>> gc_t_, hdiag_t_;
  std::vector<BlockMatrix6> S_t_;  // per-chunk reduced camera system (upper triangle)
  std::vector<std::vector<Vector6d>> b_t_;
};

}  // namespace detail
}  // namespace optimization
}  // namespace vitamin_e
