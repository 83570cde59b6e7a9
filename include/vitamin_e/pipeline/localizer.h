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
  int num_points = 0;   // map points offered to the solver
  int num_inliers = 0;
  std::vector<std::uint64_t> outliers;  // landmark ids the solver rejected (when ok)
};

class Localizer {
 public:
  explicit Localizer(const SystemConfig& config);
  // The frame's pose from its tracks that observe landmarks.
  PoseEstimate estimate(const FrameContext& frame, const Eigen::Isometry3d& guess) const;
  // A pose from normalized observations keyed by track id (frames seen while initializing).
  PoseEstimate estimate(const map::Map& map, const std::unordered_map<std::uint64_t, Eigen::Vector2d>& xy,
                        const Eigen::Isometry3d& guess) const;

 private:
  PoseEstimate solve(const std::vector<Eigen::Vector3d>& p_w, const std::vector<Eigen::Vector2d>& xy,
                     const std::vector<std::uint64_t>& ids, const Eigen::Isometry3d& guess) const;
  geometry::PnpConfig pnp_;
  int min_inliers_;
  double min_inlier_ratio_;
};

}  // namespace vitamin_e::pipeline
