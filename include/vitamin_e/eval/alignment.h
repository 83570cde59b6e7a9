#pragma once
// Timestamp association and closed-form trajectory alignment (Umeyama 1991):
// the similarity (or rigid) transform minimising sum_i |dst_i - (s R src_i + t)|^2.
#include <cstddef>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "vitamin_e/eval/trajectory.h"

namespace vitamin_e::eval {

// p -> scale * R * p + t.
struct Sim3 {
  double scale = 1.0;
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();

  Eigen::Vector3d apply(const Eigen::Vector3d& p) const { return scale * R * p + t; }
  // A pose T_w_c of the source frame into the target frame: rotation R * R_w_c,
  // position apply(t_w_c) (the scale changes positions only).
  Eigen::Isometry3d apply(const Eigen::Isometry3d& T_w_c) const;
  Sim3 inverse() const;
};

// Least-squares Sim(3) (with_scale) or SE(3) mapping src onto dst (3xN, N >= 3
// non-collinear for a unique answer). Reflections are excluded (det R = +1).
// Throws std::invalid_argument if sizes differ or N < 3, or src has no spread.
Sim3 umeyamaAlignment(const Eigen::Matrix3Xd& src, const Eigen::Matrix3Xd& dst, bool with_scale = true);

// Index pairs (estimate index, ground-truth index). Each estimate pose takes
// the nearest ground-truth pose in time if |dt| <= max_dt (no interpolation);
// a ground-truth pose is used at most once (closest pairs win). Both inputs
// must be sorted by time; the result is sorted by estimate index.
using Association = std::vector<std::pair<std::size_t, std::size_t>>;
Association associate(const Trajectory& estimate, const Trajectory& ground_truth, double max_dt = 0.02);

}  // namespace vitamin_e::eval
