#include "vitamin_e/eval/alignment.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <tuple>

#include <Eigen/SVD>

namespace vitamin_e::eval {

Eigen::Isometry3d Sim3::apply(const Eigen::Isometry3d& T_w_c) const {
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  out.linear() = R * T_w_c.linear();
  out.translation() = apply(Eigen::Vector3d(T_w_c.translation()));
  return out;
}

Sim3 Sim3::inverse() const {
  Sim3 inv;
  inv.scale = 1.0 / scale;
  inv.R = R.transpose();
  inv.t = -inv.scale * (inv.R * t);
  return inv;
}

Sim3 umeyamaAlignment(const Eigen::Matrix3Xd& src, const Eigen::Matrix3Xd& dst, bool with_scale) {
  if (src.cols() != dst.cols()) throw std::invalid_argument("umeyamaAlignment: point counts differ");
  const Eigen::Index n = src.cols();
  if (n < 3) throw std::invalid_argument("umeyamaAlignment: need at least 3 point pairs");
  const Eigen::Vector3d mu_s = src.rowwise().mean();
  const Eigen::Vector3d mu_d = dst.rowwise().mean();
  const Eigen::Matrix3Xd sc = src.colwise() - mu_s;
  const Eigen::Matrix3Xd dc = dst.colwise() - mu_d;
  const double var_s = sc.squaredNorm() / static_cast<double>(n);
  if (!(var_s > 1e-20)) throw std::invalid_argument("umeyamaAlignment: source points have no spread");

  const Eigen::Matrix3d sigma = dc * sc.transpose() / static_cast<double>(n);
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(sigma, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Vector3d s_diag(1.0, 1.0, 1.0);
  // The best rotation is U S V^T with S = diag(1, 1, det(U V^T)): a reflection
  // in the unconstrained optimum becomes a flip of the least significant axis.
  if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0.0) s_diag(2) = -1.0;

  Sim3 out;
  out.R = svd.matrixU() * s_diag.asDiagonal() * svd.matrixV().transpose();
  out.scale = with_scale ? svd.singularValues().dot(s_diag) / var_s : 1.0;
  out.t = mu_d - out.scale * out.R * mu_s;
  return out;
}

Association associate(const Trajectory& estimate, const Trajectory& ground_truth, double max_dt) {
  std::vector<std::tuple<double, std::size_t, std::size_t>> candidates;
  candidates.reserve(estimate.size());
  for (std::size_t i = 0; i < estimate.size(); ++i) {
    const double t = estimate[i].t;
    auto it = std::lower_bound(ground_truth.begin(), ground_truth.end(), t,
                               [](const StampedPose& p, double v) { return p.t < v; });
    double best = max_dt;
    std::size_t best_j = ground_truth.size();
    for (auto cand : {it, it == ground_truth.begin() ? it : it - 1}) {
      if (cand == ground_truth.end()) continue;
      const double dt = std::abs(cand->t - t);
      if (dt <= best) {
        best = dt;
        best_j = static_cast<std::size_t>(cand - ground_truth.begin());
      }
    }
    if (best_j < ground_truth.size()) candidates.emplace_back(best, i, best_j);
  }
  std::sort(candidates.begin(), candidates.end());
  std::vector<bool> used(ground_truth.size(), false);
  Association pairs;
  for (const auto& [dt, i, j] : candidates) {
    if (used[j]) continue;
    used[j] = true;
    pairs.emplace_back(i, j);
  }
  std::sort(pairs.begin(), pairs.end());
  return pairs;
}

}  // namespace vitamin_e::eval
