#pragma once
// Dominant flow: robust affine fit y = A x + b to point pairs, minimizing
// sum rho(|y_i - (A x_i + b)|) with the Geman-McClure kernel
// rho(r) = r^2 / (r^2 + sigma^2) by Gauss-Newton / IRLS. Initialized with the
// pure translation that has the largest kernel support among the pairs (a
// mode, robust to far more than 50% outliers), then sigma is annealed from
// sigma_start down to sigma_final.
#include <Eigen/Core>
#include <vector>

namespace vitamin_e::tracking {

struct AffineFitConfig {
  double sigma_start = 30.0;  // [px]
  double sigma_final = 3.0;   // [px]
  int iterations = 5;         // IRLS iterations per annealing level
  int min_inliers = 8;        // fewer inliers (residual < 2.5 sigma_final): ok = false
};

struct AffineFit {
  Eigen::Matrix2d A = Eigen::Matrix2d::Identity();
  Eigen::Vector2d b = Eigen::Vector2d::Zero();
  int inliers = 0;
  bool ok = false;
};

AffineFit fitAffineGemanMcClure(const std::vector<Eigen::Vector2d>& x, const std::vector<Eigen::Vector2d>& y,
                                const AffineFitConfig& config);

// The same IRLS started from a given (A, b) (no mode search), annealing sigma
// from sigma_start to sigma_final; used to refine a flow with many pairs.
AffineFit refineAffineGemanMcClure(const std::vector<Eigen::Vector2d>& x, const std::vector<Eigen::Vector2d>& y,
                                   const Eigen::Matrix2d& A0, const Eigen::Vector2d& b0, const AffineFitConfig& config);

}  // namespace vitamin_e::tracking
