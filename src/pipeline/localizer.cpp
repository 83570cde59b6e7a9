#include "vitamin_e/pipeline/localizer.h"

#include <cmath>

namespace vitamin_e::pipeline {

Localizer::Localizer(const SystemConfig& config)
    : pnp_(config.pnp),
      min_inliers_(config.min_pose_inliers),
      min_inlier_ratio_(config.min_pose_inlier_ratio),
      weak_max_step_ratio_(config.weak_pose_max_step_ratio) {}

PoseEstimate Localizer::estimate(const FrameContext& frame, const map::Map& map, const Eigen::Isometry3d& guess,
                                 const Eigen::Isometry3d* T_w_last) const {
  std::vector<Eigen::Vector3d> p_w;
  std::vector<Eigen::Vector2d> xy;
  std::vector<std::uint64_t> ids;
  for (const FrameTrack& t : frame.tracks) {
    if (const map::Landmark* l = map.landmark(t.id)) {
      p_w.push_back(l->p_w);
      xy.push_back(t.xy);
      ids.push_back(l->id);
    }
  }
  return solve(p_w, xy, ids, guess, T_w_last);
}

PoseEstimate Localizer::estimate(const map::Map& map, const std::unordered_map<std::uint64_t, Eigen::Vector2d>& xy,
                                 const Eigen::Isometry3d& guess) const {
  std::vector<Eigen::Vector3d> p_w;
  std::vector<Eigen::Vector2d> obs;
  std::vector<std::uint64_t> ids;
  for (const auto& kv : xy) {
    if (const map::Landmark* l = map.landmark(kv.first)) {
      p_w.push_back(l->p_w);
      obs.push_back(kv.second);
      ids.push_back(l->id);
    }
  }
  return solve(p_w, obs, ids, guess, nullptr);
}

bool Localizer::stepAgrees(const Eigen::Isometry3d& T_w_last, const Eigen::Isometry3d& T_w_predicted,
                           const Eigen::Isometry3d& T_w_c) const {
  if (weak_max_step_ratio_ <= 1.0) return false;
  const double predicted = (T_w_predicted.translation() - T_w_last.translation()).norm();
  const double step = (T_w_c.translation() - T_w_last.translation()).norm();
  if (!(predicted > 0.0) || !std::isfinite(step)) return false;  // no velocity to compare with
  return step <= weak_max_step_ratio_ * predicted && step * weak_max_step_ratio_ >= predicted;
}

PoseEstimate Localizer::solve(const std::vector<Eigen::Vector3d>& p_w, const std::vector<Eigen::Vector2d>& xy,
                              const std::vector<std::uint64_t>& ids, const Eigen::Isometry3d& guess,
                              const Eigen::Isometry3d* T_w_last) const {
  PoseEstimate e;
  e.num_points = static_cast<int>(p_w.size());
  if (e.num_points < min_inliers_) {
    e.why = "only " + std::to_string(p_w.size()) + " tracked map points";
    return e;
  }
  const geometry::PnpResult r = geometry::solvePnpRansac(p_w, xy, pnp_, &guess);
  e.num_inliers = r.num_inliers;
  if (!r.ok || r.num_inliers < min_inliers_) {
    e.why =
        "pose estimation failed (" + std::to_string(r.num_inliers) + " inliers of " + std::to_string(p_w.size()) + ")";
    return e;
  }
  // Tracks that survived a sudden change are often wrong: a pose only a minority
  // of the tracked map points agree with is not trusted, unless it moved as the
  // motion model predicted. A wrong minority consensus (say, distant points)
  // typically shrinks or inflates the step several times (a scale jump); blur
  // that corrupts many tracks for a frame does not change the camera's speed.
  if (r.num_inliers < min_inlier_ratio_ * static_cast<double>(p_w.size())) {
    e.weak_kept = T_w_last && stepAgrees(*T_w_last, guess, r.T_w_c);
  }
  if (r.num_inliers < min_inlier_ratio_ * static_cast<double>(p_w.size()) && !e.weak_kept) {
    e.why = "weak pose: only " + std::to_string(r.num_inliers) + " of " + std::to_string(p_w.size()) +
            " tracked map points agree";
    return e;
  }
  for (std::size_t i = 0; i < ids.size(); ++i) {
    if (i < r.inliers.size() && !r.inliers[i]) e.outliers.push_back(ids[i]);
  }
  e.ok = true;
  e.T_w_c = r.T_w_c;
  return e;
}

}  // namespace vitamin_e::pipeline
