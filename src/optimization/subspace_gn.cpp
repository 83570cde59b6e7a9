#include "vitamin_e/optimization/subspace_gn.h"

#include <Eigen/Dense>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "subspace_gn_impl.h"
#include "vitamin_e/common/timing.h"

namespace vitamin_e {
namespace optimization {

void BaOptions::validate() const {
  if (!(robust_sigma_px > 0.0)) throw std::invalid_argument("robust_sigma_px must be > 0");
  if (max_sweeps < 0) throw std::invalid_argument("max_sweeps must be >= 0");
  if (!(tolerance >= 0.0)) throw std::invalid_argument("tolerance must be >= 0");
  if (threads < 1) throw std::invalid_argument("threads must be >= 1");
  if (camera_iterations < 1) throw std::invalid_argument("camera_iterations must be >= 1");
  if (plain_gs_passes < 1) throw std::invalid_argument("plain_gs_passes must be >= 1");
  if (!(camera_gs_tolerance >= 0.0)) throw std::invalid_argument("camera_gs_tolerance must be >= 0");
  if (!(initial_lambda >= 0.0)) throw std::invalid_argument("initial_lambda must be >= 0");
  if (point_iterations < 0) throw std::invalid_argument("point_iterations must be >= 0");
  if (point_extrapolation < 0) throw std::invalid_argument("point_extrapolation must be >= 0");
  if (!(point_tolerance >= 0.0)) throw std::invalid_argument("point_tolerance must be >= 0");
  if (max_retries < 0) throw std::invalid_argument("max_retries must be >= 0");
}

namespace detail {

namespace {
constexpr double kSpinUs = 100.0;    // a worker spins this long for the next loop before sleeping
constexpr int kChunksPerThread = 8;  // chunks per parallel loop and thread (< 2^16 in all)
inline void cpuRelax() {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_ia32_pause();
#else
  std::this_thread::yield();
#endif
}
}  // namespace

WorkerPool::WorkerPool(int threads) : n_(std::max(1, threads)) {
  workers_.reserve(n_ - 1);
  for (int t = 1; t < n_; ++t) workers_.emplace_back([this] { loop(); });
}

WorkerPool::~WorkerPool() {
  stop_.store(true);
  state_.store(static_cast<std::uint64_t>(++gen_) << 32);
  { std::lock_guard<std::mutex> lock(m_); }
  cv_.notify_all();
  for (auto& w : workers_) w.join();
}

void WorkerPool::dispatch(int chunks) {
  done_.store(0, std::memory_order_relaxed);
  const std::uint64_t v = (static_cast<std::uint64_t>(++gen_) << 32) | (static_cast<std::uint64_t>(chunks) << 16);
  state_.store(v);  // seq_cst, against sleepers_ below (a sleeping worker sees v or is woken)
  if (sleepers_.load() > 0) {
    { std::lock_guard<std::mutex> lock(m_); }
    cv_.notify_all();
  }
  work(v);
  for (int spin = 0; done_.load(std::memory_order_acquire) != chunks; ++spin) {
    if (spin < 4096) cpuRelax();
    else std::this_thread::yield();  // a worker holding a chunk was descheduled
  }
}

void WorkerPool::work(std::uint64_t v) {
  const std::uint32_t gen = static_cast<std::uint32_t>(v >> 32);
  const int chunks = static_cast<int>((v >> 16) & 0xffff);
  for (;;) {
    if (static_cast<std::uint32_t>(v >> 32) != gen || static_cast<int>(v & 0xffff) >= chunks) return;
    // The claim compares the whole state: it only succeeds for a chunk of this job while the job
    // is running (the caller moves on only when every chunk is done), so fn_/ctx_ are this job's.
    if (state_.compare_exchange_weak(v, v + 1, std::memory_order_acq_rel, std::memory_order_acquire)) {
      fn_(ctx_, static_cast<int>(v & 0xffff));
      done_.fetch_add(1, std::memory_order_acq_rel);
      v = state_.load(std::memory_order_acquire);
    }
  }
}

void WorkerPool::loop() {
  std::uint32_t seen = 0;
  for (;;) {
    std::uint64_t v = state_.load(std::memory_order_acquire);
    if (static_cast<std::uint32_t>(v >> 32) == seen) {
      const auto t0 = std::chrono::steady_clock::now();
      for (int spin = 0; static_cast<std::uint32_t>((v = state_.load(std::memory_order_acquire)) >> 32) == seen;
           ++spin) {
        cpuRelax();
        if ((spin & 63) != 63 ||
            std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count() < kSpinUs)
          continue;
        std::unique_lock<std::mutex> lock(m_);
        sleepers_.fetch_add(1);
        cv_.wait(lock, [&] { return static_cast<std::uint32_t>(state_.load() >> 32) != seen; });
        sleepers_.fetch_sub(1);
      }
    }
    seen = static_cast<std::uint32_t>(v >> 32);
    if (stop_.load()) return;
    work(v);
  }
}

std::vector<int> weightedSplit(const std::vector<double>& prefix, int T) {
  const int n = static_cast<int>(prefix.size()) - 1;
  std::vector<int> b(T + 1, n);
  b[0] = 0;
  for (int t = 1; t < T; ++t) {
    const double target = prefix[n] * t / T;
    b[t] = static_cast<int>(std::lower_bound(prefix.begin(), prefix.end(), target) - prefix.begin());
    b[t] = std::max(b[t - 1], std::min(b[t], n));
  }
  return b;
}

namespace {

// S += Jl^T M Jr for two camera-row pairs (2x6, column-major). Column 0 of a camera row pair
// is (A, 0) and column 1 is (0, C) (pinhole Jacobian times [I | -[p_c]x]; all zero behind the
// camera), so those two columns of the product take one term.
inline void addRank2(Matrix6d* S, const Matrix26d& Jl, const Eigen::Matrix2d& M, const Matrix26d& Jr) {
  const Eigen::Matrix<double, 6, 2> L = Jl.transpose() * M;
  S->col(0) += L.col(0) * Jr(0, 0);
  S->col(1) += L.col(1) * Jr(1, 1);
  for (int c = 2; c < 6; ++c) S->col(c) += L.col(0) * Jr(0, c) + L.col(1) * Jr(1, c);
}

}  // namespace

SubspaceGn::SubspaceGn(BaProblem& p, const BaOptions& o) : P_(p), O_(o), kernel_(o.robust_sigma_px), K_(p.K) {
  buildStructure();
  const int npf = freePoints();
  T_ = std::max(1, std::min(O_.threads, npf / 256));
  std::vector<double> w_obs(npf + 1, 0.0), w_schur(npf + 1, 0.0);
  for (int j = 0; j < npf; ++j) {
    const double k = slot_begin_[j + 1] - slot_begin_[j];
    w_obs[j + 1] = w_obs[j] + 1.0 + (pt_begin_[j + 1] - pt_begin_[j]);
    w_schur[j + 1] = w_schur[j] + 1.0 + k * (k + 1.0) / 2.0;
  }
  chunks_ = T_ > 1 ? kChunksPerThread * T_ : 1;
  split_obs_ = weightedSplit(w_obs, chunks_);
  split_schur_ = weightedSplit(w_schur, chunks_);
  if (T_ > 1) pool_.reset(new WorkerPool(T_));
}

void SubspaceGn::run(int* sweeps, bool* converged, double* lambda_out) {
  *sweeps = 0;
  *converged = false;
  double lambda = O_.initial_lambda;
  if (cams_.empty() && pts_.empty()) {
    *converged = true;
    return;
  }
  double cost = linearize();
  initial_active_cost_ = cost;
  for (int sweep = 0; sweep < O_.max_sweeps; ++sweep) {
    ++*sweeps;
    bool accepted = false;
    double new_cost = cost;
    for (int attempt = 0; attempt <= O_.max_retries; ++attempt) {
      solveStep(lambda);
      saveState();
      applyStep();
      new_cost = activeCost();
      if (new_cost < cost) {
        accepted = true;
        lambda = std::max(lambda * 0.7, 1e-12);  // slow decrease: fewer rejected steps under GM
        break;
      }
      restoreState();
      ++rejected_;
      lambda = std::max(lambda * 10.0, 1e-8);
    }
    if (!accepted) {
      *converged = cost <= 1e-20 * static_cast<double>(std::max<size_t>(1, pt_obs_.size()));
      break;
    }
    if (O_.point_iterations > 0) new_cost -= refinePoints(O_.point_iterations);
    const double rel = (cost - new_cost) / std::max(cost, 1e-300);
    cost = new_cost;
    if (rel < O_.tolerance) {
      *converged = true;
      break;
    }
    if (sweep + 1 < O_.max_sweeps) cost = linearize();
  }
  *lambda_out = lambda;
}

void SubspaceGn::solveStep(double lambda) {
  const int ncf = freeCameras();
  Hd_.resize(ncf);
  for (int i = 0; i < ncf; ++i) {
    // Marquardt damping on the diagonal of the whole H_cc: + lambda diag(H_cc) + eps.
    Hd_[i] = Hcc_[i];
    Hd_[i].diagonal() += hdiag_[i] * lambda + Vector6d::Constant(1e-12 * (1.0 + hdiag_[i].sum()));
    dc_[i].setZero();
  }
  const bool schur = O_.use_schur && ncf > 0;
  // Eq. 11 with the points eliminated: the 6x6 blocks of the reduced camera system
  // S_il = H_cc,i [i==l] - sum_j H_cp,ij H_pp,j^-1 H_pc,jl and b_i = -g_c,i + sum_j H_cp,ij H_pp,j^-1 g_p,j.
  // With H_cp,ij = Jc_ij^T Wjp_ij (two residual rows), a point's term for the camera pair (i, l)
  // is Jc_ij^T M Jc_lj with the 2x2 M = Wjp_ij H_pp,j^-1 Wjp_lj^T: accumulated point by point
  // into the upper block triangle (per thread, then summed), then mirrored.
  const int T = chunks_;
  if (schur) {
    S_t_.resize(T);
    b_t_.resize(T);
    for (int t = 0; t < T; ++t) {
      S_t_[t].resize(ncf);
      b_t_[t].assign(ncf, Vector6d::Zero());
    }
  }
  forChunks(split_schur_, [&](int begin, int end, int t) {
    BlockMatrix6* S = schur ? &S_t_[t] : nullptr;
    std::vector<Vector6d>* bt = schur ? &b_t_[t] : nullptr;
    for (int j = begin; j < end; ++j) {
      Eigen::Matrix3d H = Hpp_[j];
      H.diagonal() = H.diagonal() * (1.0 + lambda) + Eigen::Vector3d::Constant(1e-12 * (1.0 + H.trace()));
      const Eigen::Matrix3d Hi = H.inverse();
      Hpp_inv_[j] = Hi;
      dp_[j].setZero();
      if (!schur) continue;
      const Eigen::Vector3d hg = Hi * gp_[j];
      const int s0 = slot_begin_[j], s1 = slot_begin_[j + 1];
      for (int s = s0; s < s1; ++s) {
        const int cs = slot_cam_[s];
        const Matrix23d Z = Wjp_[s] * Hi;
        (*bt)[cs].noalias() += Jc_[s].transpose() * (Wjp_[s] * hg);
        // Diagonal block, with the observation's own H_cc = Jc^T w Jc folded in:
        // Jc^T (w I - M) Jc, M symmetric 2x2; the full 6x6 product (vectorizes better than a triangle).
        {
          Eigen::Matrix2d M = -(Z * Wjp_[s].transpose());
          M.diagonal().array() += slot_w_[s];
          addRank2(&S->at(cs, cs), Jc_[s], M, Jc_[s]);
        }
        for (int u = s + 1; u < s1; ++u) {
          const int cu = slot_cam_[u];
          const Eigen::Matrix2d M = -(Z * Wjp_[u].transpose());  // -M_su; M_us = M_su^T
          if (cs < cu) {
            addRank2(&S->at(cs, cu), Jc_[s], M, Jc_[u]);
          } else {
            const Eigen::Matrix<double, 6, 2> L = Jc_[u].transpose() * M.transpose();
            Matrix6d X = L * Jc_[s];
            if (cs == cu) X += X.transpose().eval();  // two observations of a point in one camera
            S->at(cu, cs) += X;
          }
        }
      }
    }
  });
  if (ncf == 0) {
    pointUpdates();
    return;
  }
  if (O_.use_schur) {
    S_.resize(ncf);
    for (int i = 0; i < ncf; ++i) {
      b_[i] = -gc_[i];
      for (int t = 0; t < T; ++t) b_[i] += b_t_[t][i];
      for (int l = i; l < ncf; ++l) {
        Matrix6d& Sil = S_.at(i, l);
        Sil = S_t_[0].at(i, l);
        for (int t = 1; t < T; ++t) Sil += S_t_[t].at(i, l);
      }
      S_.at(i, i) += Hd_[i];
    }
    for (int i = 0; i < ncf; ++i)
      for (int l = i + 1; l < ncf; ++l) S_.at(l, i) = S_.at(i, l).transpose();
    if (O_.camera_solver == BaOptions::CameraSolver::kConjugateGradient)
      solveBlockPcg(S_, b_, O_.camera_iterations, O_.camera_gs_tolerance, &dc_);
    else solveBlockGaussSeidel(S_, b_, O_.camera_iterations, O_.camera_gs_tolerance, &dc_);
    pointUpdates();
    return;
  }
  // Plain Eq. 11 / Eq. 12 block Gauss-Seidel: camera blocks with the points' current
  // updates, then the point blocks with the cameras' updates, repeated.
  std::vector<Eigen::LDLT<Matrix6d>> solvers(ncf);
  for (int i = 0; i < ncf; ++i) solvers[i].compute(Hd_[i]);
  for (int pass = 0; pass < O_.plain_gs_passes; ++pass) {
    double max_change = 0.0, max_update = 0.0;
    for (int i = 0; i < ncf; ++i) {
      Vector6d rhs = -gc_[i];
      for (int a = cam_begin_[i]; a < cam_begin_[i + 1]; ++a) {
        const int s = cam_slots_[a];
        rhs.noalias() -= Jc_[s].transpose() * (Wjp_[s] * dp_[slot_point_[s]]);
      }
      const Vector6d d = solvers[i].solve(rhs);
      max_change = std::max(max_change, (d - dc_[i]).lpNorm<Eigen::Infinity>());
      max_update = std::max(max_update, d.lpNorm<Eigen::Infinity>());
      dc_[i] = d;
    }
    pointUpdates();
    if (max_change <= O_.camera_gs_tolerance * max_update) break;
  }
}

void SubspaceGn::pointUpdates() {
  forChunks(split_obs_, [&](int begin, int end, int) {
    for (int j = begin; j < end; ++j) {
      Eigen::Vector3d rhs = gp_[j];
      if (O_.use_schur) {
        Eigen::Vector3d q = Eigen::Vector3d::Zero();
        for (int s = slot_begin_[j]; s < slot_begin_[j + 1]; ++s)
          q.noalias() += Wjp_[s].transpose() * (Jc_[s] * dc_[slot_cam_[s]]);
        rhs += q;
      } else {
        for (int s = slot_begin_[j]; s < slot_begin_[j + 1]; ++s)
          rhs.noalias() += Wjp_[s].transpose() * (Jc_[s] * dc_[slot_cam_[s]]);
      }
      dp_[j].noalias() = -Hpp_inv_[j] * rhs;
    }
  });
}

}  // namespace detail

namespace detail {

void SubspaceGn::covariance(BaSummary* summary) {
  const int ncf = freeCameras();
  const int npf = freePoints();
  summary->camera_covariance.assign(P_.cameras.size(), Matrix6d::Zero());
  summary->camera_covariance_valid.assign(P_.cameras.size(), false);
  summary->residual_variance = 0.0;
  if (ncf == 0 || ncf > 100) return;
  // The blocks of run()'s last linearization: at the solution, or one step before it when the
  // sweeps ran out (relinearizing would cost as much as another sweep, for a change of the
  // order of that last step).
  // The residual variance over the inliers, |r| < 3 robust sigma (outliers have ~no weight in S
  // but would dominate a plain variance): c = sum_in |r|^2 / (2 m_in - 6 n_c - 3 n_p), from the
  // final residuals of the observations touching a free variable. Weighted or median-based
  // scales are biased low here (few observations per point: the fit absorbs most of their
  // residuals), by 2x and more at 1 px noise (test_optimization_covariance).
  const double inlier_px = 3.0 * std::sqrt(kernel_.sigma2);
  double sum_s = 0.0;
  int m = 0;
  for (std::size_t k = 0; k < summary->residual_px.size(); ++k) {
    const double r = summary->residual_px[k];
    if (fixed_norm_[k] >= 0.0 || !(r < inlier_px)) continue;
    sum_s += r * r;
    ++m;
  }
  const int dof = 2 * m - 6 * ncf - 3 * npf;
  if (dof <= 0) return;
  const double sigma2 = sum_s / dof;
  // Dense reduced camera system (6 ncf square; the per-frame BA has one free camera):
  // S = H_cc - sum_j H_cp,j H_pp,j^-1 H_pc,j, H_cp = Jc^T Wjp per slot. With use_schur, Hcc_
  // holds only the observations of fixed points, so the slots' own Jc^T w Jc are added here.
  // Given the points (BaOptions::Covariance::kGivenPoints): H_cc alone, block diagonal.
  const bool with_points = O_.covariance == BaOptions::Covariance::kWithPoints;
  const int n = 6 * ncf;
  Eigen::MatrixXd S = Eigen::MatrixXd::Zero(n, n);
  for (int i = 0; i < ncf; ++i) S.block<6, 6>(6 * Eigen::Index{i}, 6 * Eigen::Index{i}) = Hcc_[i];
  for (int j = 0; j < npf; ++j) {
    Eigen::Matrix3d H = Hpp_[j];
    H.diagonal() += Eigen::Vector3d::Constant(1e-12 * (1.0 + H.trace()));
    const Eigen::Matrix3d Hi = H.inverse();
    for (int s = slot_begin_[j]; s < slot_begin_[j + 1]; ++s) {
      const int cs = slot_cam_[s];
      if (O_.use_schur)
        S.block<6, 6>(6 * Eigen::Index{cs}, 6 * Eigen::Index{cs}).noalias() += Jc_[s].transpose() * slot_w_[s] * Jc_[s];
      if (!with_points) continue;
      const Matrix23d Z = Wjp_[s] * Hi;
      for (int u = slot_begin_[j]; u < slot_begin_[j + 1]; ++u) {
        const Eigen::Matrix2d M = Z * Wjp_[u].transpose();
        S.block<6, 6>(6 * Eigen::Index{cs}, 6 * Eigen::Index{slot_cam_[u]}).noalias() -=
            Jc_[s].transpose() * M * Jc_[u];
      }
    }
  }
  S = 0.5 * (S + S.transpose()).eval();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(S);
  if (eig.info() != Eigen::Success) return;
  const double lo = eig.eigenvalues().minCoeff(), hi = eig.eigenvalues().maxCoeff();
  if (!(lo > 1e-12 * hi) || !std::isfinite(hi)) return;  // a gauge freedom or an unobserved direction
  const Eigen::MatrixXd S_inv =
      eig.eigenvectors() * eig.eigenvalues().cwiseInverse().asDiagonal() * eig.eigenvectors().transpose();
  for (int i = 0; i < ncf; ++i) {
    Matrix6d C = sigma2 * S_inv.block<6, 6>(6 * Eigen::Index{i}, 6 * Eigen::Index{i});
    summary->camera_covariance[cams_[i]] = 0.5 * (C + C.transpose());
    summary->camera_covariance_valid[cams_[i]] = true;
  }
  summary->residual_variance = sigma2;
}

double SubspaceGn::finish(std::vector<double>* residual_px) const {
  // The formulas of baCost and baResidualNorms; the constant part is buildStructure's.
  residual_px->resize(P_.observations.size());
  double cost = fixed_cost_;
  Eigen::Vector2d r;
  for (size_t k = 0; k < P_.observations.size(); ++k) {
    if (fixed_norm_[k] >= 0.0) {
      (*residual_px)[k] = fixed_norm_[k];
    } else if (baResidual(P_, P_.observations[k], &r)) {
      const double s = r.squaredNorm();
      cost += kernel_.rho(s);
      (*residual_px)[k] = std::sqrt(s);
    } else {
      cost += kernel_.sigma2;
      (*residual_px)[k] = std::numeric_limits<double>::infinity();
    }
  }
  return cost;
}

}  // namespace detail

BaSummary solveSubspaceGaussNewton(BaProblem& problem, const BaOptions& options) {
  options.validate();
  problem.validate();
  BaSummary summary;
  // time_ms covers setup and sweeps, not the final reporting (final cost, residuals).
  const auto start = TimingClock::now();
  detail::SubspaceGn solver(problem, options);
  summary.free_cameras = solver.freeCameras();
  summary.free_points = solver.freePoints();
  summary.active_observations = solver.activeObservations();
  solver.run(&summary.sweeps, &summary.converged, &summary.final_lambda);
  // The initial cost comes from the solver's own first pass (the constant part plus the first
  // linearization) instead of another pass over every observation.
  summary.initial_cost = solver.initialCost();
  summary.rejected_steps = solver.rejectedSteps();
  summary.time_ms = elapsedMs(start);
  const double final_cost = solver.finish(&summary.residual_px);
  summary.final_cost = final_cost;
  if (options.compute_covariance) {
    const auto t0 = TimingClock::now();
    solver.covariance(&summary);
    summary.covariance_ms = elapsedMs(t0);
  }
  return summary;
}


}  // namespace optimization
}  // namespace vitamin_e
