#include "vitamin_e/tracking/affine_flow.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace vitamin_e::tracking {
namespace {

// One weighted least-squares solve of y = A x + b with Geman-McClure IRLS
// weights w = sigma^2 / (r^2 + sigma^2)^2 (d rho / d r^2, up to a constant).
bool irlsStep(const std::vector<Eigen::Vector2d>& x, const std::vector<Eigen::Vector2d>& y, double sigma,
              Eigen::Matrix2d* A, Eigen::Vector2d* b, bool affine) {
  const double s2 = sigma * sigma;
  Eigen::Matrix3d N = Eigen::Matrix3d::Zero();
  Eigen::Matrix<double, 3, 2> R = Eigen::Matrix<double, 3, 2>::Zero();
  double wsum = 0.0;
  for (size_t i = 0; i < x.size(); ++i) {
    const Eigen::Vector2d r = y[i] - (*A * x[i] + *b);
    const double q = r.squaredNorm() + s2;
    const double w = s2 / (q * q);
    const Eigen::Vector3d h(x[i].x(), x[i].y(), 1.0);
    N.noalias() += w * h * h.transpose();
    R.noalias() += w * h * y[i].transpose();
    wsum += w;
  }
  if (wsum <= 0.0) return false;
  if (!affine) {  // translation only (A fixed)
    Eigen::Vector2d t = Eigen::Vector2d::Zero();
    for (size_t i = 0; i < x.size(); ++i) {
      const Eigen::Vector2d r = y[i] - (*A * x[i] + *b);
      const double q = r.squaredNorm() + s2;
      t += (s2 / (q * q)) * r;
    }
    *b += t / wsum;
    return true;
  }
  Eigen::LDLT<Eigen::Matrix3d> ldlt(N);
  if (ldlt.info() != Eigen::Success) return false;
  // Conditioning guard: degenerate (collinear) weighted support.
  const Eigen::Vector3d d = ldlt.vectorD();
  if (d.minCoeff() <= 1e-9 * std::max(1e-30, d.maxCoeff())) return false;
  const Eigen::Matrix<double, 3, 2> P = ldlt.solve(R);  // rows: A^T (2), b^T
  if (!P.allFinite()) return false;
  A->row(0) = P.col(0).head<2>().transpose();
  A->row(1) = P.col(1).head<2>().transpose();
  *b = P.row(2).transpose();
  return true;
}

}  // namespace

AffineFit refineAffineGemanMcClure(const std::vector<Eigen::Vector2d>& x, const std::vector<Eigen::Vector2d>& y,
                                   const Eigen::Matrix2d& A0, const Eigen::Vector2d& b0, const AffineFitConfig& c,
                                   bool translation_first);

AffineFit fitAffineGemanMcClure(const std::vector<Eigen::Vector2d>& x, const std::vector<Eigen::Vector2d>& y,
                                const AffineFitConfig& c) {
  if (x.size() != y.size()) throw std::invalid_argument("fitAffineGemanMcClure: x and y differ in size");
  AffineFit fit;
  const size_t n = x.size();
  if (n == 0) return fit;
  // Mode of the translations under the kernel at sigma_start: robust start.
  const double s2 = c.sigma_start * c.sigma_start;
  const size_t stride = std::max<size_t>(1, n / 200);
  double best_score = -1.0;
  for (size_t i = 0; i < n; i += stride) {
    const Eigen::Vector2d t = y[i] - x[i];
    double score = 0.0;
    for (size_t j = 0; j < n; ++j) {
      const double r2 = (y[j] - x[j] - t).squaredNorm();
      score += s2 / (r2 + s2);
    }
    if (score > best_score) {
      best_score = score;
      fit.b = t;
    }
  }
  return refineAffineGemanMcClure(x, y, Eigen::Matrix2d::Identity(), fit.b, c, true);
}

AffineFit refineAffineGemanMcClure(const std::vector<Eigen::Vector2d>& x, const std::vector<Eigen::Vector2d>& y,
                                   const Eigen::Matrix2d& A0, const Eigen::Vector2d& b0, const AffineFitConfig& c) {
  return refineAffineGemanMcClure(x, y, A0, b0, c, false);
}

AffineFit refineAffineGemanMcClure(const std::vector<Eigen::Vector2d>& x, const std::vector<Eigen::Vector2d>& y,
                                   const Eigen::Matrix2d& A0, const Eigen::Vector2d& b0, const AffineFitConfig& c,
                                   bool translation_first) {
  if (x.size() != y.size()) throw std::invalid_argument("refineAffineGemanMcClure: x and y differ in size");
  AffineFit fit;
  const size_t n = x.size();
  if (n == 0) return fit;
  Eigen::Matrix2d A = A0;
  Eigen::Vector2d b = b0;
  const bool affine = n >= 3;
  double sigma = std::max(c.sigma_start, c.sigma_final);
  // First settle the translation at the coarse scale, then fit the full affine.
  if (translation_first) {
    for (int it = 0; it < c.iterations; ++it) irlsStep(x, y, sigma, &A, &b, false);
  }
  while (true) {
    for (int it = 0; it < c.iterations; ++it) {
      Eigen::Matrix2d A1 = A;
      Eigen::Vector2d b1 = b;
      if (!irlsStep(x, y, sigma, &A1, &b1, affine)) break;
      A = A1;
      b = b1;
    }
    if (sigma <= c.sigma_final) break;
    sigma = std::max(0.5 * sigma, c.sigma_final);
  }
  const double thr2 = std::pow(2.5 * c.sigma_final, 2);
  int inl = 0;
  for (size_t i = 0; i < n; ++i) inl += (y[i] - (A * x[i] + b)).squaredNorm() < thr2 ? 1 : 0;
  fit.A = A;
  fit.b = b;
  fit.inliers = inl;
  fit.ok = inl >= c.min_inliers && inl >= 3;
  return fit;
}

}  // namespace vitamin_e::tracking
