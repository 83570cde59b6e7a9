#pragma once
// Subspace Gauss-Newton bundle adjustment (VITAMIN-E, Yokozuka et al. CVPR 2019, Sec. 3.2,
// Eq. 11-12, and the supplementary's variable elimination).
//
// One SWEEP:
//  1. Linearize every observation that touches a free variable at the current estimate
//     (analytic Jacobians, Geman-McClure IRLS weights w = rho'(|r|^2)): per camera the 6x6
//     block H_cc and g_c, per point the 3x3 block H_pp and g_p, per (camera, point) pair the
//     6x3 coupling H_cp = Jc^T (w Jp), kept as its two camera rows and two weighted point rows
//     (rank 2: the Schur complement is accumulated through the 2-dimensional residual space).
//     Nothing larger than 6x6 is ever inverted or factorized.
//  2. Camera blocks (Eq. 11). With use_schur (default) each camera update eliminates the points
//     it sees (the supplementary's variable elimination): the 6x6 blocks of the reduced camera
//     system S_il = H_cc,i [i==l] - sum_j H_cp,ij H_pp,j^-1 H_pc,jl (only pairs of free cameras
//     sharing a point are non-zero) and b_i = -g_c,i + sum_j H_cp,ij H_pp,j^-1 g_p,j are
//     accumulated, then solved block-wise: by block Gauss-Seidel over the 6x6 camera blocks
//     (the paper's iteration) or by conjugate gradients preconditioned with the 6x6 diagonal
//     blocks (default: Gauss-Seidel needs hundreds of passes when a chain of cameras is free).
//     Without use_schur it is the paper's plain Eq. 11/12 Gauss-Seidel (camera blocks with the
//     points' current updates, then point blocks), repeated plain_gs_passes times.
//  3. Point blocks (Eq. 12): each 3x3 update given the camera updates (independent per point).
//  4. The step is applied (T_w_c <- T_w_c * expSE3(dc), p_w <- p_w + dp) and kept only if the
//     robust cost decreased; otherwise the LM damping lambda (Marquardt: each block's diagonal
//     is scaled by 1 + lambda) grows and the step is recomputed from the same linearization.
//  5. (point_iterations > 0) After an accepted step, relinearized Gauss-Newton steps on each
//     point alone (Eq. 12 with the cameras fixed), kept per point only if its cost decreases:
//     under Geman-McClure the slow modes are mostly single points, and these steps are cheap.
//     The IRLS model over-estimates the curvature of Geman-McClure, so a point's step falls
//     short; with point_extrapolation > 0 an accepted step is doubled while the point's cost
//     keeps decreasing (a line search along the Gauss-Newton direction), and a point stops
//     iterating once a step gains less than point_tolerance of its cost.
// Threads (BaOptions::threads > 1): every loop over the free points (linearization, Schur
// accumulation, point updates, the step's cost, the point refinement) runs on a pool created
// once per solve, over fixed chunks of points that the threads claim as they go; sums into the
// camera blocks and costs are kept per chunk and added in chunk order, so a result does not
// depend on the scheduling and differs from the 1-thread result only by rounding. Below 256
// free points per thread it uses fewer threads (one for < 512 points).
// Stops when the relative cost decrease of an accepted step is below `tolerance`, when no
// damped step decreases the cost, or after max_sweeps.
//
// Gauge: only the `fixed` flags of the problem are honoured (see ba_problem.h and
// ba_window.h); fix at least the two oldest cameras for a monocular problem.
#include <vector>

#include "vitamin_e/optimization/ba_problem.h"

namespace vitamin_e {
namespace optimization {

struct BaOptions {
  double robust_sigma_px = 2.0;  // Geman-McClure sigma
  int max_sweeps = 20;           // linearizations at most (the SLAM sets it per solve: pipeline.ba_*_sweeps)
  double tolerance = 1e-6;       // relative cost change of an accepted sweep
  int threads = 1;               // threads for the loops over points (see above)
  bool use_schur = true;         // eliminate the points inside each camera update
  // How the reduced camera system (use_schur) is solved: block Gauss-Seidel (stops when
  // max |change| <= camera_gs_tolerance * max |update|) or block-Jacobi preconditioned CG
  // (stops when |residual| <= camera_gs_tolerance * |rhs|). Both only factorize 6x6 blocks; a
  // pass costs (free cameras)^2 6x6 products, negligible next to the linearization.
  enum class CameraSolver { kGaussSeidel, kConjugateGradient };
  CameraSolver camera_solver = CameraSolver::kConjugateGradient;
  int camera_iterations = 200;         // max passes (GS) / iterations (CG)
  double camera_gs_tolerance = 1e-10;  // (name kept for configs; used by both solvers)
  int plain_gs_passes = 10;            // without use_schur: passes of the plain Eq. 11/12 Gauss-Seidel
  double initial_lambda = 1e-4;        // LM damping (relative to the block diagonals)
  int max_retries = 8;                 // damped re-solves per sweep before giving up
  // After each accepted sweep, this many relinearized Gauss-Newton steps on every point alone
  // (Eq. 12 with the cameras fixed; cheap, independent per point, threaded). Off: in the SLAM's
  // per-frame BA their cost bought no accuracy.
  int point_iterations = 0;
  // Per point, after an accepted step: up to this many doublings of the step while its cost
  // keeps decreasing (the IRLS steps of Geman-McClure fall short; 0 = plain Gauss-Newton).
  int point_extrapolation = 0;
  // A point stops iterating when a step decreases its cost by less than this fraction.
  double point_tolerance = 0.0;
  // Also return each free camera's 6x6 covariance (BaSummary::camera_covariance): from the
  // last linearization, the reduced camera system S = H_cc - H_cp H_pp^-1 H_pc (IRLS blocks
  // J^T W J, points eliminated, no damping) and cov = c S^-1 (camera blocks of the inverse), c
  // the residual variance of the inliers (|r| < 3 robust_sigma_px) at the solution:
  // c = sum |r|^2 / (2 m - 6 n_c - 3 n_p) over those m observations. The last linearization is
  // at the solution, or one step before it when max_sweeps ran out. Checked against a dense
  // reference and against the spread of the solution over noise draws
  // (test_optimization_covariance: within 30 %, on the conservative side); the IRLS-weighted
  // variance would under-state the spread by 2x and more at 1 px noise. Off by default: the
  // solve is the same either way; this adds the reduced system's assembly and a dense 6 n_c
  // inverse (about 0.2 ms for 3,000 points and one free camera, see covariance_ms).
  bool compute_covariance = false;
  // What that covariance describes.
  //   kWithPoints: the camera relative to the fixed cameras, the points' own uncertainty
  //     included (S above): the error of the camera's pose in the map.
  //   kGivenPoints: the camera's own measurements alone, the points taken as they are
  //     (H_cc, no elimination): the error that differs between cameras seeing the same
  //     points, of which the error of the motion between consecutive frames is made
  //     (their common map error cancels in it).
  enum class Covariance { kWithPoints, kGivenPoints };
  Covariance covariance = Covariance::kGivenPoints;
  void validate() const;  // throws std::invalid_argument naming the key
};

struct BaSummary {
  double initial_cost = 0.0;  // baCost at the start (all observations)
  double final_cost = 0.0;    // baCost at the end
  int sweeps = 0;             // linearizations performed
  int rejected_steps = 0;     // damped steps that did not decrease the cost (re-solved)
  double time_ms = 0.0;
  bool converged = false;           // relative cost change fell below tolerance
  std::vector<double> residual_px;  // per observation, final |r| in pixels
  int free_cameras = 0;
  int free_points = 0;
  int active_observations = 0;  // observations touching a free variable
  double final_lambda = 0.0;
  // With BaOptions::compute_covariance, per camera of the problem (same index; empty otherwise):
  // the covariance of the camera's right perturbation delta = (rho, phi) at the solution
  // (T_w_c * expSE3(delta), delta in the camera frame; problem units^2 and rad^2), as
  // BaOptions::covariance says (relative to the fixed cameras, or given the points). Zero and not valid for fixed cameras, and for every camera
  // when S is not positive definite (no fixed camera, too few observations), when the inliers
  // leave no degree of freedom, or when there are more than 100 free cameras.
  std::vector<Eigen::Matrix<double, 6, 6>> camera_covariance;
  std::vector<bool> camera_covariance_valid;
  double residual_variance = 0.0;  // c of the covariance [px^2] (0 when not computed)
  double covariance_ms = 0.0;      // its cost (not in time_ms)
};

BaSummary solveSubspaceGaussNewton(BaProblem& problem, const BaOptions& options);

}  // namespace optimization
}  // namespace vitamin_e
