#pragma once
// Camera pose against the map: P3P + RANSAC (or the motion model's guess when
// the points agree with it), refined with the Geman-McClure kernel.
#include <cstdint>
#include <string>
#include <unordered_map>
#include <vector>

#include <Eigen/Geometry>

#include "vitamin_e/geometry/pnp.h"
#include "vitamin_e/map/map.h"
#include "vitamin_e/pipeline/frame_context.h"
#include "vitamin_e/pipeline/system_config.h"

namespace vitamin_e::pipeline {

struct PoseEstimate {
  bool ok = false;
  std::string why;  // when not ok
  Eigen::Isometry3d T_w_c = Eigen::Isometry3d::Identity();
  int num_points = 0;  // map points offered to the solver
  int num_inliers = 0;
  // A minority of the tracked map points agreed, but the pose moved the way
  // the motion model predicted, so it was kept.
  bool weak_kept = false;
  std::vector<std::uint64_t> outliers;  // landmark ids the solver rejected (when ok)
};

class Localizer {
 public:
  explicit Localizer(const SystemConfig& config);
  // The frame's pose from its tracks that observe landmarks. T_w_last: the
  // pose the guess was predicted from (constant velocity), or null when the
  // guess is not a prediction; it lets a weakly supported pose through when
  // its step agrees with the predicted one.
  PoseEstimate estimate(const FrameContext& frame, const map::Map& map, const Eigen::Isometry3d& guess,
                        const Eigen::Isometry3d* T_w_last = nullptr) const;
  // A pose from normalized observations keyed by track id (frames seen while initializing).
  PoseEstimate estimate(const map::Map& map, const std::unordered_map<std::uint64_t, Eigen::Vector2d>& xy,
                        const Eigen::Isometry3d& guess) const;

 private:
  // The pose's step from T_w_last within a factor weak_pose_max_step_ratio of
  // the predicted step.
  bool stepAgrees(const Eigen::Isometry3d& T_w_last, const Eigen::Isometry3d& T_w_predicted,
                  const Eigen::Isometry3d& T_w_c) const;
  PoseEstimate solve(const std::vector<Eigen::Vector3d>& p_w, const std::vector<Eigen::Vector2d>& xy,
                     const std::vector<std::uint64_t>& ids, const Eigen::Isometry3d& guess,
                     const Eigen::Isometry3d* T_w_last) const;
  geometry::PnpConfig pnp_;
  int min_inliers_;
  double min_inlier_ratio_;
  double weak_max_step_ratio_;
};

}  // namespace vitamin_e::pipeline
