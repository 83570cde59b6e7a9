#include "vitamin_e/geometry/triangulation.h"

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace vitamin_e {
namespace geometry {

void TriangulationConfig::validate() const {
  if (!(focal_px > 0.0)) throw std::invalid_argument("focal_px must be > 0");
  if (!(min_parallax_deg >= 0.0)) throw std::invalid_argument("min_parallax_deg must be >= 0");
  if (!(max_reproj_error_px > 0.0)) throw std::invalid_argument("max_reproj_error_px must be > 0");
  if (!(min_depth >= 0.0)) throw std::invalid_argument("min_depth must be >= 0");
  if (gn_iterations < 0) throw std::invalid_argument("gn_iterations must be >= 0");
}

double parallaxDeg(const Eigen::Vector3d& center_a, const Eigen::Vector3d& center_b, const Eigen::Vector3d& p_w) {
  const Eigen::Vector3d a = (p_w - center_a).normalized();
  const Eigen::Vector3d b = (p_w - center_b).normalized();
  // atan2 of |a x b| and a.b is accurate for small angles.
  return std::atan2(a.cross(b).norm(), a.dot(b)) * 180.0 / M_PI;
}

bool triangulateDlt(const std::vector<Eigen::Isometry3d>& T_w_c, const std::vector<Eigen::Vector2d>& xy,
                    Eigen::Vector3d* p_w) {
  const int n = static_cast<int>(T_w_c.size());
  if (n < 2 || static_cast<int>(xy.size()) != n) return false;
  // The null vector of the 2n x 4 DLT matrix A is the eigenvector of A^T A with
  // the least eigenvalue: a 4x4 solve instead of an SVD of A (rows are uniform
  // in normalized coordinates, so squaring the condition costs no useful digits
  // before the Gauss-Newton refinement).
  Eigen::Matrix4d AtA = Eigen::Matrix4d::Zero();
  for (int k = 0; k < n; ++k) {
    const Eigen::Isometry3d T_c_w = T_w_c[k].inverse();
    Eigen::Matrix<double, 3, 4> P;
    P.leftCols<3>() = T_c_w.linear();
    P.col(3) = T_c_w.translation();
    const Eigen::RowVector4d u = xy[k].x() * P.row(2) - P.row(0);
    const Eigen::RowVector4d v = xy[k].y() * P.row(2) - P.row(1);
    AtA.noalias() += u.transpose() * u + v.transpose() * v;
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> eig(AtA);
  if (eig.info() != Eigen::Success) return false;
  const Eigen::Vector4d X = eig.eigenvectors().col(0);  // eigenvalues ascending
  if (std::abs(X(3)) < 1e-12 * X.head<3>().norm()) return false;
  *p_w = X.head<3>() / X(3);
  return p_w->allFinite();
}

TriangulationResult triangulatePoint(const std::vector<Eigen::Isometry3d>& T_w_c,
                                     const std::vector<Eigen::Vector2d>& xy, const TriangulationConfig& config) {
  TriangulationResult res;
  const int n = static_cast<int>(T_w_c.size());
  if (n < 2 || static_cast<int>(xy.size()) != n) {
    res.failed = TriangulationCheck::kViews;
    res.reason = "need at least two views with one observation each";
    return res;
  }
  Eigen::Vector3d p;
  if (!triangulateDlt(T_w_c, xy, &p)) {
    res.failed = TriangulationCheck::kLinear;
    res.reason = "linear triangulation failed (point at infinity)";
    return res;
  }
  std::vector<Eigen::Isometry3d> T_c_w(n);
  for (int k = 0; k < n; ++k) T_c_w[k] = T_w_c[k].inverse();

  // Gauss-Newton on the normalized reprojection error (3x3 normal equations).
  for (int it = 0; it < config.gn_iterations; ++it) {
    Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
    Eigen::Vector3d g = Eigen::Vector3d::Zero();
    double cost = 0.0;
    bool bad = false;
    for (int k = 0; k < n; ++k) {
      const Eigen::Vector3d pc = T_c_w[k] * p;
      if (pc.z() <= 1e-12) {
        bad = true;
        break;
      }
      const double iz = 1.0 / pc.z();
      const Eigen::Vector2d r = xy[k] - Eigen::Vector2d(pc.x() * iz, pc.y() * iz);
      Eigen::Matrix<double, 2, 3> Jproj;
      Jproj << iz, 0.0, -pc.x() * iz * iz, 0.0, iz, -pc.y() * iz * iz;
      const Eigen::Matrix<double, 2, 3> J = -Jproj * T_c_w[k].linear();
      H.noalias() += J.transpose() * J;
      g.noalias() += J.transpose() * r;
      cost += r.squaredNorm();
    }
    if (bad) break;  // DLT solution behind a camera: keep it, checks below report it
    const Eigen::Vector3d dp = H.ldlt().solve(-g);
    if (!dp.allFinite()) break;
    // Accept only decreasing steps.
    const Eigen::Vector3d p_new = p + dp;
    double cost_new = 0.0;
    for (int k = 0; k < n; ++k) {
      const Eigen::Vector3d pc = T_c_w[k] * p_new;
      cost_new += (xy[k] - pc.head<2>() / pc.z()).squaredNorm();
    }
    if (!(cost_new <= cost)) break;
    p = p_new;
    if (dp.norm() < 1e-12 * (1.0 + p.norm())) break;
  }
  res.p_w = p;

  res.cheirality_ok = true;
  res.reproj_error_px.resize(n);
  double max_err = 0.0;
  for (int k = 0; k < n; ++k) {
    const Eigen::Vector3d pc = T_c_w[k] * p;
    if (!(pc.z() > config.min_depth)) res.cheirality_ok = false;
    const double e = (pc.z() > 0.0) ? (xy[k] - pc.head<2>() / pc.z()).norm() * config.focal_px
                                    : std::numeric_limits<double>::infinity();
    res.reproj_error_px[k] = e;
    max_err = std::max(max_err, e);
  }
  for (int a = 0; a < n; ++a)
    for (int b = a + 1; b < n; ++b)
      res.parallax_deg = std::max(res.parallax_deg, parallaxDeg(T_w_c[a].translation(), T_w_c[b].translation(), p));

  if (!res.cheirality_ok) {
    res.failed = TriangulationCheck::kCheirality;
    res.reason = "cheirality: point behind a camera";
  } else if (res.parallax_deg < config.min_parallax_deg) {
    res.failed = TriangulationCheck::kParallax;
    res.reason = "parallax too small";
  } else if (max_err > config.max_reproj_error_px) {
    res.failed = TriangulationCheck::kReprojection;
    res.reason = "reprojection error too large";
  } else {
    res.ok = true;
  }
  return res;
}

}  // namespace geometry
}  // namespace vitamin_e
