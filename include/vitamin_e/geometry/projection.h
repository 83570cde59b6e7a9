#pragma once
// The reprojection Jacobians (the pinhole projection itself is camera::Pinhole) and the
// Geman-McClure kernel: shared by PnP, triangulation and bundle adjustment so that the math
// lives in one place.
//
// Residual model (paper Eq. 7): r = u - phi(R^T (p_w - t)) with T_w_c = (R, t).
// Camera perturbation: T_w_c <- T_w_c * expSE3(delta), delta = (rho, phi) (see lie.h).
// Then p_c = T_w_c^-1 p_w moves as dp_c/drho = -I, dp_c/dphi = [p_c]x, dp_c/dp_w = R^T.
#include <Eigen/Core>
#include <Eigen/Geometry>

#include "vitamin_e/camera/pinhole.h"
#include "vitamin_e/geometry/lie.h"

namespace vitamin_e {
namespace geometry {

using Matrix23d = Eigen::Matrix<double, 2, 3>;
using Matrix26d = Eigen::Matrix<double, 2, 6>;

// Geman-McClure in squared-pixel units: rho(s) = sigma^2 s / (sigma^2 + s), s = |r|^2.
// rho ~ s for small residuals and saturates at sigma^2 for outliers.
struct GemanMcClure {
  double sigma2 = 4.0;
  explicit GemanMcClure(double sigma_px) : sigma2(sigma_px * sigma_px) {}
  double rho(double s) const { return sigma2 * s / (sigma2 + s); }
  // rho'(s) = sigma^4 / (sigma^2 + s)^2: the IRLS weight of a residual with |r|^2 = s.
  double weight(double s) const {
    const double d = sigma2 + s;
    return sigma2 * sigma2 / (d * d);
  }
  // rho''(s) = -2 sigma^4 / (sigma^2 + s)^3.
  double second(double s) const {
    const double d = sigma2 + s;
    return -2.0 * sigma2 * sigma2 / (d * d * d);
  }
};

// Jacobians of r = uv - project(T_w_c^-1 p_w) w.r.t. the camera perturbation delta (2x6)
// and the point p_w (2x3), given p_c = T_w_c^-1 p_w and R_w_c.
inline void reprojectionJacobians(const camera::Pinhole& K, const Eigen::Vector3d& p_c, const Eigen::Matrix3d& R_w_c,
                                  Matrix26d* J_cam, Matrix23d* J_point) {
  const Matrix23d Jproj = K.projectPointJacobian(p_c);
  if (J_cam) {
    J_cam->leftCols<3>() = Jproj;                // -(Jproj * -I)
    J_cam->rightCols<3>() = -Jproj * skew(p_c);  // -(Jproj * [p_c]x)
  }
  if (J_point) *J_point = -Jproj * R_w_c.transpose();
}

}  // namespace geometry
}  // namespace vitamin_e
