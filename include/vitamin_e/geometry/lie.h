#pragma once
// SO(3) / SE(3) Lie-group math in ONE place: free functions on Eigen types.
//
// Conventions
// - so(3) tangent: rotation vector phi (axis * angle), R = expSO3(phi).
// - se(3) tangent: xi = (rho, phi) with the TRANSLATION PART FIRST (xi.head<3>() = rho,
//   xi.tail<3>() = phi). expSE3(xi) = [expSO3(phi), leftJacobianSO3(phi) * rho; 0 1].
// - Perturbations used by the solvers are on the right of T_w_c:
//   T_w_c <- T_w_c * expSE3(delta), i.e. delta is expressed in the camera frame.
// - Right Jacobian Jr(phi): expSO3(phi + d) ~= expSO3(phi) * expSO3(Jr(phi) d);
//   left Jacobian Jl(phi) = Jr(-phi): expSO3(phi + d) ~= expSO3(Jl(phi) d) * expSO3(phi).
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>

namespace vitamin_e {
namespace geometry {

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

// [v]x such that skew(a) * b = a.cross(b).
inline Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return m;
}

// Inverse of skew: the vector of the antisymmetric part of m.
inline Eigen::Vector3d unskew(const Eigen::Matrix3d& m) {
  return 0.5 * Eigen::Vector3d(m(2, 1) - m(1, 2), m(0, 2) - m(2, 0), m(1, 0) - m(0, 1));
}

// Rodrigues' formula; Taylor expansion near zero.
inline Eigen::Matrix3d expSO3(const Eigen::Vector3d& phi) {
  const double theta2 = phi.squaredNorm();
  const Eigen::Matrix3d K = skew(phi);
  double a, b;  // R = I + a K + b K^2
  if (theta2 < 1e-10) {
    a = 1.0 - theta2 / 6.0;
    b = 0.5 - theta2 / 24.0;
  } else {
    const double theta = std::sqrt(theta2);
    a = std::sin(theta) / theta;
    b = (1.0 - std::cos(theta)) / theta2;
  }
  return Eigen::Matrix3d::Identity() + a * K + b * K * K;
}

// Rotation vector of R, angle in [0, pi]. Robust near 0 and near pi.
inline Eigen::Vector3d logSO3(const Eigen::Matrix3d& R) {
  const double c = std::max(-1.0, std::min(1.0, 0.5 * (R.trace() - 1.0)));
  const double theta = std::acos(c);
  if (theta < 1e-5) {
    return unskew(R) * (1.0 + theta * theta / 6.0);  // sin(theta) ~ theta
  }
  if (M_PI - theta < 1e-4) {
    // Near pi: the symmetric part of (R + I) / 2 is ~ a a^T (its antisymmetric part is
    // O(pi - theta) and would bias the axis); take its column of largest norm.
    const Eigen::Matrix3d B = 0.25 * (R + R.transpose()) + 0.5 * Eigen::Matrix3d::Identity();
    int k = 0;
    B.diagonal().maxCoeff(&k);
    Eigen::Vector3d axis = B.col(k) / std::sqrt(std::max(B(k, k), 1e-300));
    axis.normalize();
    // Fix the sign with the antisymmetric part (valid unless exactly pi).
    if (axis.dot(unskew(R)) < 0.0) axis = -axis;
    return axis * theta;
  }
  return unskew(R) * (theta / std::sin(theta));
}

// Right Jacobian of SO(3).
inline Eigen::Matrix3d rightJacobianSO3(const Eigen::Vector3d& phi) {
  const double theta2 = phi.squaredNorm();
  const Eigen::Matrix3d K = skew(phi);
  double a, b;  // Jr = I - a K + b K^2
  if (theta2 < 1e-10) {
    a = 0.5 - theta2 / 24.0;
    b = 1.0 / 6.0 - theta2 / 120.0;
  } else {
    const double theta = std::sqrt(theta2);
    a = (1.0 - std::cos(theta)) / theta2;
    b = (theta - std::sin(theta)) / (theta2 * theta);
  }
  return Eigen::Matrix3d::Identity() - a * K + b * K * K;
}

inline Eigen::Matrix3d leftJacobianSO3(const Eigen::Vector3d& phi) { return rightJacobianSO3(-phi); }

// Inverse of the right Jacobian of SO(3) (closed form).
inline Eigen::Matrix3d rightJacobianInvSO3(const Eigen::Vector3d& phi) {
  const double theta2 = phi.squaredNorm();
  const Eigen::Matrix3d K = skew(phi);
  double b;  // Jr^-1 = I + 0.5 K + b K^2
  if (theta2 < 1e-10) {
    b = 1.0 / 12.0 + theta2 / 720.0;
  } else {
    const double theta = std::sqrt(theta2);
    b = 1.0 / theta2 - (1.0 + std::cos(theta)) / (2.0 * theta * std::sin(theta));
  }
  return Eigen::Matrix3d::Identity() + 0.5 * K + b * K * K;
}

inline Eigen::Matrix3d leftJacobianInvSO3(const Eigen::Vector3d& phi) { return rightJacobianInvSO3(-phi); }

// se(3) exponential, xi = (rho, phi).
inline Eigen::Isometry3d expSE3(const Vector6d& xi) {
  const Eigen::Vector3d rho = xi.head<3>();
  const Eigen::Vector3d phi = xi.tail<3>();
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = expSO3(phi);
  T.translation() = leftJacobianSO3(phi) * rho;
  return T;
}

// se(3) logarithm, returns (rho, phi).
inline Vector6d logSE3(const Eigen::Isometry3d& T) {
  const Eigen::Vector3d phi = logSO3(T.linear());
  Vector6d xi;
  xi.head<3>() = leftJacobianInvSO3(phi) * T.translation();
  xi.tail<3>() = phi;
  return xi;
}

// Re-orthonormalizes the rotation of T (after many compositions).
inline Eigen::Isometry3d normalizedIsometry(const Eigen::Isometry3d& T) {
  Eigen::Isometry3d out = T;
  out.linear() = Eigen::Quaterniond(T.linear()).normalized().toRotationMatrix();
  return out;
}

// Rotation angle between two rotations in radians.
inline double rotationAngle(const Eigen::Matrix3d& Ra, const Eigen::Matrix3d& Rb) {
  return logSO3(Ra.transpose() * Rb).norm();
}

}  // namespace geometry
}  // namespace vitamin_e
