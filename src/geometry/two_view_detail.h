#pragma once
// Internal to vitamin_e_geometry: the residual of the two-view refinement (two_view.cpp) and its
// analytic Jacobian, and the pose choice from an essential matrix, in a header of their own so
// that test_geometry_two_view checks the Jacobian against numeric derivatives and the pose
// choice against cv::recoverPose.
#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <vector>

#include "vitamin_e/geometry/lie.h"

namespace vitamin_e {
namespace geometry {
namespace detail {

// Sampson distance (normalized units) of x1^T E x0 and its denominator.
inline double sampson(const Eigen::Matrix3d& E, const Eigen::Vector3d& x0, const Eigen::Vector3d& x1, double* denom) {
  const Eigen::Vector3d Ex0 = E * x0;
  const Eigen::Vector3d Etx1 = E.transpose() * x1;
  *denom = std::sqrt(std::max(Ex0.head<2>().squaredNorm() + Etx1.head<2>().squaredNorm(), 1e-30));
  return x1.dot(Ex0) / *denom;
}

// The columns B of the update t <- normalize(t + B d): an orthonormal basis of the plane normal
// to the unit vector t.
inline Eigen::Matrix<double, 3, 2> tangentBasis(const Eigen::Vector3d& t) {
  Eigen::Matrix<double, 3, 2> B;
  B.col(0) = t.unitOrthogonal();
  B.col(1) = t.cross(B.col(0));
  return B;
}

// Jacobian of s * x1^T [t]x R x0 (s = focal / the Sampson denominator, frozen) with respect to
// (w, d) of R <- R expSO3(w), t <- normalize(t + B d), at w = 0, d = 0:
//   d/dw = -s x1^T [t]x R [x0]x,   d/dd = s ((R x0) x x1)^T B.
inline Eigen::Matrix<double, 1, 5> sampsonJacobian(const Eigen::Matrix3d& R, const Eigen::Vector3d& t,
                                                   const Eigen::Matrix<double, 3, 2>& B, const Eigen::Vector3d& x0,
                                                   const Eigen::Vector3d& x1, double s) {
  Eigen::Matrix<double, 1, 5> J;
  J.leftCols<3>() = -s * x1.transpose() * skew(t) * R * skew(x0);
  J.rightCols<2>() = s * ((R * x0).cross(x1)).transpose() * B;
  return J;
}

// The relative pose (R, t: x_c1 = R x_c0 + t, |t| = 1) an essential matrix stands for: of its
// four decompositions the one that puts the most masked correspondences (normalized
// coordinates) in front of both cameras, nearer than max_depth (in units of |t|). Returns that
// count; 0 (R, t untouched) for a degenerate E. Each point's depths are the least-squares
// solution of z1 x1 = z0 R x0 + t, a 2x2 solve: cv::recoverPose triangulates every point by an
// SVD for each of the four, most of the initializer's time (docs/PERFORMANCE.md, Profile).
int poseFromEssential(const Eigen::Matrix3d& E, const std::vector<Eigen::Vector2d>& xy0,
                      const std::vector<Eigen::Vector2d>& xy1, const std::vector<bool>& mask, double max_depth,
                      Eigen::Matrix3d* R, Eigen::Vector3d* t);

}  // namespace detail
}  // namespace geometry
}  // namespace vitamin_e
