#include "vitamin_e/optimization/subspace_gn.h"

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <thread>

#include "vitamin_e/geometry/lie.h"
#include "vitamin_e/geometry/projection.h"
#include "vitamin_e/optimization/block_solvers.h"

namespace vitamin_e {
namespace optimization {

using geometry::Matrix6d;
using geometry::Vector6d;
using Matrix63d = Eigen::Matrix<double, 6, 3>;

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
  if (max_retries < 0) throw std::invalid_argument("max_retries must be >= 0");
}

namespace {

constexpr double kMinDepth = 1e-9;

// Runs f(begin, end, thread_index) over [0, n) split in `threads` contiguous chunks.
template <typename F>
void parallelFor(int n, int threads, F&& f) {
  const int t = std::max(1, std::min(threads, n / 256));
  if (t <= 1) {
    f(0, n, 0);
    return;
  }
  std::vector<std::thread> pool;
  pool.reserve(t - 1);
  for (int k = 1; k < t; ++k) pool.emplace_back([&, k] { f(n * k / t, n * (k + 1) / t, k); });
  f(0, n / t, 0);
  for (auto& th : pool) th.join();
}

class SubspaceGn {
 public:
  SubspaceGn(BaProblem& p, const BaOptions& o) : P_(p), O_(o), kernel_(o.robust_sigma_px) {
    K_.fx = p.fx;
    K_.fy = p.fy;
    K_.cx = p.cx;
    K_.cy = p.cy;
    buildStructure();
  }

  int freeCameras() const { return static_cast<int>(cams_.size()); }
  int freePoints() const { return static_cast<int>(pts_.size()); }
  int rejectedSteps() const { return rejected_; }
  int activeObservations() const { return static_cast<int>(pt_obs_.size() + cam_only_obs_.size()); }

  // Runs the sweeps; returns {sweeps, converged, lambda}.
  void run(int* sweeps, bool* converged, double* lambda_out) {
    *sweeps = 0;
    *converged = false;
    double lambda = O_.initial_lambda;
    if (cams_.empty() && pts_.empty()) {
      *converged = true;
      return;
    }
    double cost = linearize();
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
          lambda = std::max(lambda * 0.3, 1e-12);
          break;
        }
        restoreState();
        ++rejected_;
        lambda = std::max(lambda * 10.0, 1e-8);
      }
      if (!accepted) {
        *converged = cost <= 1e-20 * std::max<size_t>(1, pt_obs_.size());
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

 private:
  void buildStructure() {
    const int nc = static_cast<int>(P_.cameras.size());
    const int np = static_cast<int>(P_.points.size());
    cam_var_.assign(nc, -1);
    pt_var_.assign(np, -1);
    for (int c = 0; c < nc; ++c)
      if (!P_.cameras[c].fixed) {
        cam_var_[c] = static_cast<int>(cams_.size());
        cams_.push_back(c);
      }
    // Free points: not fixed and observed at least once.
    std::vector<int> count(np, 0);
    for (const BaObservation& o : P_.observations) ++count[o.point];
    for (int p = 0; p < np; ++p)
      if (!P_.points[p].fixed && count[p] > 0) {
        pt_var_[p] = static_cast<int>(pts_.size());
        pts_.push_back(p);
      }
    const int npf = static_cast<int>(pts_.size());
    const int ncf = static_cast<int>(cams_.size());
    // Point-major observation lists; slots = (free camera, free point) pairs, point-major.
    std::vector<int> per_point(npf + 1, 0);
    for (const BaObservation& o : P_.observations) {
      const int j = pt_var_[o.point];
      if (j >= 0) ++per_point[j + 1];
    }
    for (int j = 0; j < npf; ++j) per_point[j + 1] += per_point[j];
    pt_begin_ = per_point;
    pt_obs_.assign(per_point[npf], -1);
    for (size_t k = 0; k < P_.observations.size(); ++k) {
      const BaObservation& o = P_.observations[k];
      const int j = pt_var_[o.point];
      if (j >= 0) {
        pt_obs_[per_point[j]++] = static_cast<int>(k);
      } else if (cam_var_[o.camera] >= 0) {
        cam_only_obs_.push_back(static_cast<int>(k));
      }
    }
    obs_slot_.assign(pt_obs_.size(), -1);
    slot_begin_.assign(npf + 1, 0);
    std::vector<int> cam_count(ncf + 1, 0);
    for (int j = 0; j < npf; ++j) {
      slot_begin_[j] = static_cast<int>(slot_cam_.size());
      for (int a = pt_begin_[j]; a < pt_begin_[j + 1]; ++a) {
        const int ci = cam_var_[P_.observations[pt_obs_[a]].camera];
        if (ci < 0) continue;
        obs_slot_[a] = static_cast<int>(slot_cam_.size());
        slot_cam_.push_back(ci);
        slot_point_.push_back(j);
        ++cam_count[ci + 1];
      }
    }
    slot_begin_[npf] = static_cast<int>(slot_cam_.size());
    for (int i = 0; i < ncf; ++i) cam_count[i + 1] += cam_count[i];
    cam_begin_ = cam_count;
    cam_slots_.assign(slot_cam_.size(), -1);
    for (size_t s = 0; s < slot_cam_.size(); ++s) cam_slots_[cam_count[slot_cam_[s]]++] = static_cast<int>(s);

    Hcc_.resize(ncf);
    gc_.resize(ncf);
    b_.resize(ncf);
    dc_.resize(ncf);
    Hpp_.resize(npf);
    gp_.resize(npf);
    Hpp_inv_.resize(npf);
    dp_.resize(npf);
    q_.resize(npf);
    Hcp_.resize(slot_cam_.size());
    if (O_.use_schur) Y_.resize(slot_cam_.size());
    // Constant cost of the observations with nothing free.
    fixed_cost_ = 0.0;
    Eigen::Vector2d r;
    for (const BaObservation& o : P_.observations)
      if (cam_var_[o.camera] < 0 && pt_var_[o.point] < 0)
        fixed_cost_ += baResidual(P_, o, &r) ? kernel_.rho(r.squaredNorm()) : kernel_.sigma2;
  }

  // Builds all blocks at the current estimate; returns the robust cost of the active part.
  double linearize() {
    const int ncf = freeCameras();
    const int npf = freePoints();
    cacheCameras();
    const int T = std::max(1, O_.threads);
    std::vector<std::vector<Matrix6d>> Hcc_t(T, std::vector<Matrix6d>(ncf, Matrix6d::Zero()));
    std::vector<std::vector<Vector6d>> gc_t(T, std::vector<Vector6d>(ncf, Vector6d::Zero()));
    std::vector<double> cost_t(T, 0.0);
    parallelFor(npf, T, [&](int begin, int end, int t) {
      double cost = 0.0;
      for (int j = begin; j < end; ++j) {
        Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
        Eigen::Vector3d g = Eigen::Vector3d::Zero();
        const Eigen::Vector3d& p = P_.points[pts_[j]].p_w;
        for (int a = pt_begin_[j]; a < pt_begin_[j + 1]; ++a) {
          const BaObservation& o = P_.observations[pt_obs_[a]];
          const Eigen::Matrix3d& Rt = Rt_[o.camera];
          const Eigen::Vector3d p_c = Rt * (p - t_[o.camera]);
          const int s = obs_slot_[a];
          if (p_c.z() <= kMinDepth) {
            cost += kernel_.sigma2;
            if (s >= 0) Hcp_[s].setZero();
            continue;
          }
          const Eigen::Vector2d r = o.uv - K_.project(p_c);
          const double sq = r.squaredNorm();
          cost += kernel_.rho(sq);
          double w;
          const Eigen::Matrix2d W = weightMatrix(r, sq, &w);
          geometry::Matrix23d Jp;
          geometry::Matrix26d Jc;
          geometry::reprojectionJacobians(K_, p_c, R_[o.camera], s >= 0 ? &Jc : nullptr, &Jp);
          const Eigen::Matrix<double, 3, 2> JpTW = Jp.transpose() * W;
          H.noalias() += JpTW * Jp;
          g.noalias() += w * (Jp.transpose() * r);
          if (s >= 0) {
            const Eigen::Matrix<double, 6, 2> JcTW = Jc.transpose() * W;
            const int ci = slot_cam_[s];
            Hcc_t[t][ci].noalias() += JcTW * Jc;
            gc_t[t][ci].noalias() += w * (Jc.transpose() * r);
            Hcp_[s].noalias() = JcTW * Jp;
          }
        }
        Hpp_[j] = H;
        gp_[j] = g;
      }
      cost_t[t] = cost;
    });
    double cost = 0.0;
    for (int t = 0; t < T; ++t) cost += cost_t[t];
    for (int i = 0; i < ncf; ++i) {
      Hcc_[i].setZero();
      gc_[i].setZero();
      for (int t = 0; t < T; ++t) {
        Hcc_[i] += Hcc_t[t][i];
        gc_[i] += gc_t[t][i];
      }
    }
    // Free cameras observing fixed points.
    for (int k : cam_only_obs_) {
      const BaObservation& o = P_.observations[k];
      const int ci = cam_var_[o.camera];
      const Eigen::Vector3d p_c = Rt_[o.camera] * (P_.points[o.point].p_w - t_[o.camera]);
      if (p_c.z() <= kMinDepth) {
        cost += kernel_.sigma2;
        continue;
      }
      const Eigen::Vector2d r = o.uv - K_.project(p_c);
      const double sq = r.squaredNorm();
      cost += kernel_.rho(sq);
      double w;
      const Eigen::Matrix2d W = weightMatrix(r, sq, &w);
      geometry::Matrix26d Jc;
      geometry::reprojectionJacobians(K_, p_c, R_[o.camera], &Jc, nullptr);
      Hcc_[ci].noalias() += Jc.transpose() * W * Jc;
      gc_[ci].noalias() += w * (Jc.transpose() * r);
    }
    return cost;
  }

  // IRLS weight matrix of one residual (Hessian block J^T W J, gradient w J^T r, w = rho').
  // The second-order term of Geman-McClure (rho'' < 0) is dropped, as Ceres does; using it
  // (floored to stay positive definite) was tried and converged worse on the benchmark.
  Eigen::Matrix2d weightMatrix(const Eigen::Vector2d&, double sq, double* w) const {
    *w = kernel_.weight(sq);
    return *w * Eigen::Matrix2d::Identity();
  }

  // Computes dc_, dp_ for the damping lambda from the current linearization.
  void solveStep(double lambda) {
    const int ncf = freeCameras();
    const int npf = freePoints();
    parallelFor(npf, O_.threads, [&](int begin, int end, int) {
      for (int j = begin; j < end; ++j) {
        Eigen::Matrix3d H = Hpp_[j];
        H.diagonal() = H.diagonal() * (1.0 + lambda) + Eigen::Vector3d::Constant(1e-12 * (1.0 + H.trace()));
        Hpp_inv_[j] = H.inverse();
        q_[j].setZero();
        dp_[j].setZero();
        if (O_.use_schur)
          for (int s = slot_begin_[j]; s < slot_begin_[j + 1]; ++s) Y_[s].noalias() = Hcp_[s] * Hpp_inv_[j];
      }
    });
    std::vector<Matrix6d> Hd(ncf);
    for (int i = 0; i < ncf; ++i) {
      Hd[i] = Hcc_[i];
      Hd[i].diagonal() = Hd[i].diagonal() * (1.0 + lambda) + Vector6d::Constant(1e-12 * (1.0 + Hd[i].trace()));
      dc_[i].setZero();
    }
    if (ncf == 0) {
      pointUpdates();
      return;
    }
    if (O_.use_schur) {
      // Eq. 11 with the points eliminated: the 6x6 blocks of the reduced camera system
      // S_il = H_cc,i [i==l] - sum_j H_cp,ij H_pp,j^-1 H_pc,jl and b_i = -g_c,i + sum_j Y_ij g_p,j,
      // accumulated row by row (rows are independent; the upper triangle, then mirrored).
      S_.resize(ncf);
      parallelFor(ncf, O_.threads, [&](int begin, int end, int) {
        for (int i = begin; i < end; ++i) {
          S_.at(i, i) = Hd[i];
          b_[i] = -gc_[i];
          for (int a = cam_begin_[i]; a < cam_begin_[i + 1]; ++a) {
            const int s = cam_slots_[a];
            const int j = slot_point_[s];
            b_[i].noalias() += Y_[s] * gp_[j];
            for (int t = slot_begin_[j]; t < slot_begin_[j + 1]; ++t)
              if (slot_cam_[t] >= i) S_.at(i, slot_cam_[t]).noalias() -= Y_[s] * Hcp_[t].transpose();
          }
        }
      });
      for (int i = 0; i < ncf; ++i)
        for (int l = i + 1; l < ncf; ++l) S_.at(l, i) = S_.at(i, l).transpose();
      if (O_.camera_solver == BaOptions::CameraSolver::kConjugateGradient)
        solveBlockPcg(S_, b_, O_.camera_iterations, O_.camera_gs_tolerance, &dc_);
      else
        solveBlockGaussSeidel(S_, b_, O_.camera_iterations, O_.camera_gs_tolerance, &dc_);
      parallelFor(npf, O_.threads, [&](int begin, int end, int) {
        for (int j = begin; j < end; ++j)
          for (int s = slot_begin_[j]; s < slot_begin_[j + 1]; ++s)
            q_[j].noalias() += Hcp_[s].transpose() * dc_[slot_cam_[s]];
      });
      pointUpdates();
      return;
    }
    // Plain Eq. 11 / Eq. 12 block Gauss-Seidel: camera blocks with the points' current
    // updates, then the point blocks with the cameras' updates, repeated.
    std::vector<Eigen::LDLT<Matrix6d>> solvers(ncf);
    for (int i = 0; i < ncf; ++i) solvers[i].compute(Hd[i]);
    for (int pass = 0; pass < O_.plain_gs_passes; ++pass) {
      double max_change = 0.0, max_update = 0.0;
      for (int i = 0; i < ncf; ++i) {
        Vector6d rhs = -gc_[i];
        for (int a = cam_begin_[i]; a < cam_begin_[i + 1]; ++a) {
          const int s = cam_slots_[a];
          rhs.noalias() -= Hcp_[s] * dp_[slot_point_[s]];
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

  // Eq. 12 relinearized: Gauss-Newton steps on each point alone with the cameras fixed (each
  // point's cost only involves its own observations, so every step is checked and kept per
  // point). Returns the total cost decrease.
  double refinePoints(int iterations) {
    cacheCameras();
    const int T = std::max(1, O_.threads);
    std::vector<double> gain_t(T, 0.0);
    parallelFor(freePoints(), T, [&](int begin, int end, int t) {
      for (int j = begin; j < end; ++j) {
        Eigen::Vector3d p = P_.points[pts_[j]].p_w;
        auto eval = [&](const Eigen::Vector3d& x, Eigen::Matrix3d* H, Eigen::Vector3d* g) {
          double c = 0.0;
          if (H) H->setZero(), g->setZero();
          for (int a = pt_begin_[j]; a < pt_begin_[j + 1]; ++a) {
            const BaObservation& o = P_.observations[pt_obs_[a]];
            const Eigen::Vector3d p_c = Rt_[o.camera] * (x - t_[o.camera]);
            if (p_c.z() <= kMinDepth) {
              c += kernel_.sigma2;
              continue;
            }
            const Eigen::Vector2d r = o.uv - K_.project(p_c);
            const double sq = r.squaredNorm();
            c += kernel_.rho(sq);
            if (!H) continue;
            geometry::Matrix23d Jp;
            geometry::reprojectionJacobians(K_, p_c, R_[o.camera], nullptr, &Jp);
            const double w = kernel_.weight(sq);
            H->noalias() += w * Jp.transpose() * Jp;
            g->noalias() += w * Jp.transpose() * r;
          }
          return c;
        };
        double lambda = O_.initial_lambda;
        Eigen::Matrix3d H;
        Eigen::Vector3d g;
        for (int it = 0; it < iterations; ++it) {
          const double c0 = eval(p, &H, &g);
          bool improved = false;
          for (int attempt = 0; attempt < 3 && !improved; ++attempt) {
            Eigen::Matrix3d Hd = H;
            Hd.diagonal() = Hd.diagonal() * (1.0 + lambda) + Eigen::Vector3d::Constant(1e-12 * (1.0 + H.trace()));
            const Eigen::Vector3d dp = -(Hd.inverse() * g);
            const double c1 = eval(p + dp, nullptr, nullptr);
            if (c1 < c0) {
              p += dp;
              gain_t[t] += c0 - c1;
              lambda *= 0.3;
              improved = true;
            } else {
              lambda *= 10.0;
            }
          }
          if (!improved) break;
        }
        P_.points[pts_[j]].p_w = p;
      }
    });
    double gain = 0.0;
    for (double v : gain_t) gain += v;
    return gain;
  }

  // Eq. 12: dp_j = -H_pp^-1 (g_p + sum_i H_pc dc_i), independent per point.
  void pointUpdates() {
    parallelFor(freePoints(), O_.threads, [&](int begin, int end, int) {
      for (int j = begin; j < end; ++j) {
        Eigen::Vector3d rhs = gp_[j];
        if (O_.use_schur) {
          rhs += q_[j];
        } else {
          for (int s = slot_begin_[j]; s < slot_begin_[j + 1]; ++s)
            rhs.noalias() += Hcp_[s].transpose() * dc_[slot_cam_[s]];
        }
        dp_[j].noalias() = -Hpp_inv_[j] * rhs;
      }
    });
  }

  void cacheCameras() {
    const size_t nc = P_.cameras.size();
    Rt_.resize(nc);
    R_.resize(nc);
    t_.resize(nc);
    for (size_t c = 0; c < nc; ++c) {
      R_[c] = P_.cameras[c].T_w_c.linear();
      Rt_[c] = R_[c].transpose();
      t_[c] = P_.cameras[c].T_w_c.translation();
    }
  }

  void saveState() {
    saved_cams_.resize(cams_.size());
    saved_pts_.resize(pts_.size());
    for (size_t i = 0; i < cams_.size(); ++i) saved_cams_[i] = P_.cameras[cams_[i]].T_w_c;
    for (size_t j = 0; j < pts_.size(); ++j) saved_pts_[j] = P_.points[pts_[j]].p_w;
  }
  void restoreState() {
    for (size_t i = 0; i < cams_.size(); ++i) P_.cameras[cams_[i]].T_w_c = saved_cams_[i];
    for (size_t j = 0; j < pts_.size(); ++j) P_.points[pts_[j]].p_w = saved_pts_[j];
  }
  void applyStep() {
    for (size_t i = 0; i < cams_.size(); ++i) {
      Eigen::Isometry3d& T = P_.cameras[cams_[i]].T_w_c;
      T = geometry::normalizedIsometry(T * geometry::expSE3(dc_[i]));
    }
    for (size_t j = 0; j < pts_.size(); ++j) P_.points[pts_[j]].p_w += dp_[j];
  }

  double activeCost() {
    cacheCameras();
    const int T = std::max(1, O_.threads);
    std::vector<double> cost_t(T, 0.0);
    auto term = [&](const BaObservation& o) {
      const Eigen::Vector3d p_c = Rt_[o.camera] * (P_.points[o.point].p_w - t_[o.camera]);
      if (p_c.z() <= kMinDepth) return kernel_.sigma2;
      return kernel_.rho((o.uv - K_.project(p_c)).squaredNorm());
    };
    parallelFor(static_cast<int>(pt_obs_.size()), T, [&](int begin, int end, int t) {
      double c = 0.0;
      for (int a = begin; a < end; ++a) c += term(P_.observations[pt_obs_[a]]);
      cost_t[t] = c;
    });
    double cost = 0.0;
    for (double c : cost_t) cost += c;
    for (int k : cam_only_obs_) cost += term(P_.observations[k]);
    return cost;
  }

  BaProblem& P_;
  const BaOptions& O_;
  geometry::GemanMcClure kernel_;
  geometry::Pinhole K_;
  std::vector<int> cam_var_, pt_var_, cams_, pts_;
  std::vector<int> pt_begin_, pt_obs_, obs_slot_, cam_only_obs_;
  std::vector<int> slot_begin_, slot_cam_, slot_point_, cam_begin_, cam_slots_;
  double fixed_cost_ = 0.0;
  int rejected_ = 0;
  std::vector<Matrix6d> Hcc_;
  BlockMatrix6 S_;
  std::vector<Vector6d> gc_, b_, dc_;
  std::vector<Eigen::Matrix3d> Hpp_, Hpp_inv_, Rt_, R_;
  std::vector<Eigen::Vector3d> gp_, dp_, q_, t_, saved_pts_;
  std::vector<Matrix63d> Hcp_, Y_;
  std::vector<Eigen::Isometry3d> saved_cams_;
};

}  // namespace

BaSummary solveSubspaceGaussNewton(BaProblem& problem, const BaOptions& options) {
  options.validate();
  problem.validate();
  BaSummary summary;
  summary.initial_cost = baCost(problem, options.robust_sigma_px);
  // time_ms covers setup and sweeps, not the reporting (initial/final cost, residuals).
  const auto start = std::chrono::steady_clock::now();
  SubspaceGn solver(problem, options);
  summary.free_cameras = solver.freeCameras();
  summary.free_points = solver.freePoints();
  summary.active_observations = solver.activeObservations();
  solver.run(&summary.sweeps, &summary.converged, &summary.final_lambda);
  summary.rejected_steps = solver.rejectedSteps();
  summary.time_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  summary.final_cost = baCost(problem, options.robust_sigma_px);
  summary.residual_px = baResidualNorms(problem);
  return summary;
}

}  // namespace optimization
}  // namespace vitamin_e
