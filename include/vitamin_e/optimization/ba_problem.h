#pragma once
// Bundle-adjustment problem (paper Eq. 7): cameras T_w_c, points p_w, observations uv in
// undistorted pinhole pixels. Residual r_ij = uv_ij - phi(R_j^T (p_i - t_j)), T_w_c = (R_j, t_j),
// phi = the pinhole projection K (camera::Pinhole::projectPoint). Robust cost: Geman-McClure in px^2 units,
// rho(s) = sigma^2 s / (sigma^2 + s), s = |r|^2 (~ s for inliers, saturates at sigma^2).
//
// Gauge: a monocular BA is defined up to a similarity (7 DoF). The solvers do NOT fix anything
// by themselves: the caller marks cameras `fixed` (normally the oldest two, which fixes the
// pose and the scale; see BaWindowPolicy) and points `fixed` as needed. A problem without any
// fixed camera is still solved (damping keeps it well posed) but its gauge drifts freely.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

#include "vitamin_e/camera/pinhole.h"

namespace vitamin_e {
namespace optimization {

struct BaCamera {
  Eigen::Isometry3d T_w_c = Eigen::Isometry3d::Identity();
  bool fixed = false;
};

struct BaPoint {
  Eigen::Vector3d p_w = Eigen::Vector3d::Zero();
  bool fixed = false;
};

struct BaObservation {
  int camera = -1;
  int point = -1;
  Eigen::Vector2d uv = Eigen::Vector2d::Zero();  // undistorted pinhole pixels
};

struct BaProblem {
  camera::Pinhole K;
  std::vector<BaCamera> cameras;
  std::vector<BaPoint> points;
  std::vector<BaObservation> observations;
  // Throws std::invalid_argument on bad indices or non-positive focal lengths.
  void validate() const;
};

// Reprojection residual of one observation in pixels; a point at depth <= min_depth gets
// a huge residual (so that it saturates the robust kernel). Returns false in that case.
bool baResidual(const BaProblem& problem, const BaObservation& obs, Eigen::Vector2d* r);

// Sum over observations of Geman-McClure rho(|r|^2) (px^2). Points behind a camera count as
// sigma^2 (saturated).
double baCost(const BaProblem& problem, double robust_sigma_px);

// Per-observation |r| in pixels (infinity for points behind the camera).
std::vector<double> baResidualNorms(const BaProblem& problem);

}  // namespace optimization
}  // namespace vitamin_e
