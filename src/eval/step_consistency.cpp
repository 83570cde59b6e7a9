#include "vitamin_e/eval/step_consistency.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <stdexcept>

#include <Eigen/Cholesky>

#include "vitamin_e/eval/alignment.h"
#include "vitamin_e/geometry/lie.h"

namespace vitamin_e::eval {

namespace {

// Inverse of the standard normal CDF (Acklam's rational approximation, |error| < 1.2e-9).
double normalQuantile(double p) {
  static const double a[] = {-3.969683028665376e+01, 2.209460984245205e+02,  -2.759285104469687e+02,
                             1.383577518672690e+02,  -3.066479806614716e+01, 2.506628277459239e+00};
  static const double b[] = {-5.447609879822406e+01, 1.615858368580409e+02, -1.556989798598866e+02,
                             6.680131188771972e+01, -1.328068155288572e+01};
  static const double c[] = {-7.784894002430293e-03, -3.223964580411365e-01, -2.400758277161838e+00,
                             -2.549732539343734e+00, 4.374664141464968e+00,  2.938163982698783e+00};
  static const double d[] = {7.784695709041462e-03, 3.224671290700398e-01, 2.445134137142996e+00,
                             3.754408661907416e+00};
  if (!(p > 0.0 && p < 1.0)) throw std::invalid_argument("normalQuantile: p must be in (0, 1)");
  const double lo = 0.02425;
  if (p < lo) {
    const double q = std::sqrt(-2.0 * std::log(p));
    return (((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
           ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1.0);
  }
  if (p > 1.0 - lo) return -normalQuantile(1.0 - p);
  const double q = p - 0.5, r = q * q;
  return (((((a[0] * r + a[1]) * r + a[2]) * r + a[3]) * r + a[4]) * r + a[5]) * q /
         (((((b[0] * r + b[1]) * r + b[2]) * r + b[3]) * r + b[4]) * r + 1.0);
}

// x^T C^-1 x, or a negative number when C is not positive definite.
template <int N>
double mahalanobis2(const Eigen::Matrix<double, N, 1>& x, const Eigen::Matrix<double, N, N>& C) {
  const Eigen::LLT<Eigen::Matrix<double, N, N>> llt(0.5 * (C + C.transpose()));
  if (llt.info() != Eigen::Success) return -1.0;
  return x.dot(llt.solve(x));
}

}  // namespace

double chiSquareQuantile(double p, double k) {
  const double z = normalQuantile(p);
  const double h = 2.0 / (9.0 * k);
  return k * std::pow(1.0 - h + z * std::sqrt(h), 3);
}

StepConsistency stepConsistency(const std::vector<StepEstimate>& estimate, const Trajectory& ground_truth,
                                const StepConsistencyOptions& options) {
  Trajectory est;
  est.reserve(estimate.size());
  for (const StepEstimate& e : estimate) est.push_back({e.t, e.T_w_c});
  const Association pairs = associate(est, ground_truth, options.max_dt);
  if (pairs.size() < 2) throw std::invalid_argument("stepConsistency: fewer than two poses match the ground truth");
  // The steps between consecutive estimates that both have ground truth.
  struct Step {
    std::size_t i;  // the estimate at its end
    Eigen::Isometry3d est, truth;
  };
  std::vector<Step> steps;
  for (std::size_t k = 1; k < pairs.size(); ++k) {
    const auto [i0, j0] = pairs[k - 1];
    const auto [i1, j1] = pairs[k];
    if (i1 != i0 + 1 || !estimate[i1].has_covariance) continue;
    steps.push_back({i1, estimate[i0].T_w_c.inverse() * estimate[i1].T_w_c,
                     ground_truth[j0].T_w_c.inverse() * ground_truth[j1].T_w_c});
  }
  StepConsistency r;
  const int n = static_cast<int>(steps.size());
  const int w = std::max(1, options.scale_window);
  double sum_pos = 0.0, sum_rot = 0.0;
  int within = 0;
  for (int k = 0; k < n; ++k) {
    double len_est = 0.0, len_truth = 0.0;
    for (int m = std::max(0, k - w); m <= std::min(n - 1, k + w); ++m) {
      len_est += steps[m].est.translation().norm();
      len_truth += steps[m].truth.translation().norm();
    }
    if (!(len_truth > 0.0) || !(len_est > 0.0)) continue;
    Eigen::Isometry3d truth = steps[k].truth;
    truth.translation() *= len_est / len_truth;  // into map units
    const geometry::Vector6d delta = geometry::logSE3(truth.inverse() * steps[k].est);
    const Matrix6d& C = estimate[steps[k].i].step_covariance;
    const double nees = mahalanobis2<6>(delta, C);
    if (!(nees >= 0.0)) continue;
    r.nees.push_back(nees);
    r.stamps.push_back(estimate[steps[k].i].t);
    r.errors.push_back(delta);
    sum_pos += mahalanobis2<3>(Eigen::Vector3d(delta.head<3>()), Eigen::Matrix3d(C.topLeftCorner<3, 3>()));
    sum_rot += mahalanobis2<3>(Eigen::Vector3d(delta.tail<3>()), Eigen::Matrix3d(C.bottomRightCorner<3, 3>()));
    within += nees < chiSquareQuantile(0.95, 6.0) ? 1 : 0;
  }
  r.steps = static_cast<int>(r.nees.size());
  if (r.steps == 0) return r;
  double sum = 0.0;
  for (double v : r.nees) sum += v;
  r.mean_nees = sum / r.steps;
  r.mean_nees_position = sum_pos / r.steps;
  r.mean_nees_rotation = sum_rot / r.steps;
  r.lower = chiSquareQuantile(0.025, 6.0 * r.steps) / r.steps;
  r.upper = chiSquareQuantile(0.975, 6.0 * r.steps) / r.steps;
  std::vector<double> sorted = r.nees;
  const auto middle = sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2);
  std::nth_element(sorted.begin(), middle, sorted.end());
  r.median_nees = sorted[sorted.size() / 2];
  r.fraction_within_95 = static_cast<double>(within) / r.steps;
  return r;
}

}  // namespace vitamin_e::eval
