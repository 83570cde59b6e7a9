#include "vitamin_e/optimization/subspace_gn.h"

#include <Eigen/Dense>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include "subspace_gn_impl.h"

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

SubspaceGn::SubspaceGn(BaProblem& p, const BaOptions& o) : P_(p), O_(o), kernel_(o.robust_sigma_px) {
  K_.fx = p.fx;
  K_.fy = p.fy;
  K_.cx = p.cx;
  K_.cy = p.cy;
  buildStructure();
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

void SubspaceGn::solveStep(double lambda) {
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

void SubspaceGn::pointUpdates() {
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

}  // namespace detail

BaSummary solveSubspaceGaussNewton(BaProblem& problem, const BaOptions& options) {
  options.validate();
  problem.validate();
  BaSummary summary;
  summary.initial_cost = baCost(problem, options.robust_sigma_px);
  // time_ms covers setup and sweeps, not the reporting (initial/final cost, residuals).
  const auto start = std::chrono::steady_clock::now();
  detail::SubspaceGn solver(problem, options);
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
