// The inlined derivatives of the subspace Gauss-Newton BA
// (src/optimization/subspace_gn_rows.h, used by subspace_gn_linearize.cpp)
// against central differences of an independent residual, on random cameras,
// points and observations: d r / d p_w, d r / d camera (right perturbation
// T_w_c exp(xi), the update applyStep makes), the Geman-McClure weight as
// d rho / d s, and the assembled blocks (w J^T J, w J^T r = half the gradient
// of the robust cost).
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <random>
#include <vector>

#include "../../src/optimization/subspace_gn_rows.h"
#include "vitamin_e/geometry/lie.h"
#include "vitamin_e/geometry/projection.h"

namespace opt = vitamin_e::optimization;
namespace geo = vitamin_e::geometry;
using Eigen::Isometry3d;
using Eigen::Matrix3d;
using Eigen::Vector2d;
using Eigen::Vector3d;
using geo::Vector6d;
using Matrix26 = Eigen::Matrix<double, 2, 6>;
using Matrix23 = Eigen::Matrix<double, 2, 3>;

namespace {

constexpr double kSigma2 = 4.0;  // Geman-McClure sigma 2 px

struct Case {
  vitamin_e::camera::Pinhole K;
  Isometry3d T_w_c;
  Vector3d p_w;
  Vector2d uv;
};

// A camera somewhere, a point 1-10 units in front of it, an observation a few
// pixels off its projection (residuals of both signs, weights below 1).
Case randomCase(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Case c;
  c.K.fx = 420.0 + 40.0 * u(rng);
  c.K.fy = c.K.fx * (1.0 + 0.02 * u(rng));
  c.K.cx = 370.0 + 5.0 * u(rng);
  c.K.cy = 240.0 + 5.0 * u(rng);
  c.T_w_c =
      geo::expSE3((Vector6d() << 2 * u(rng), 2 * u(rng), 2 * u(rng), 2 * u(rng), 2 * u(rng), 2 * u(rng)).finished());
  const Vector3d p_c(1.5 * u(rng), 1.0 * u(rng), 5.5 + 4.5 * u(rng));
  c.p_w = c.T_w_c * p_c;
  c.uv = c.K.projectPoint(p_c) + Vector2d(4.0 * u(rng), 4.0 * u(rng));
  return c;
}

// The residual, computed without the code under test.
Vector2d residual(const Case& c, const Isometry3d& T_w_c, const Vector3d& p_w) {
  return c.uv - c.K.projectPoint(T_w_c.inverse() * p_w);
}
double robustCost(const Case& c, const Isometry3d& T_w_c, const Vector3d& p_w) {
  return geo::GemanMcClure(std::sqrt(kSigma2)).rho(residual(c, T_w_c, p_w).squaredNorm());
}

Matrix23 numericPointJacobian(const Case& c) {
  Matrix23 J;
  for (int k = 0; k < 3; ++k) {
    const double h = 1e-6 * (1.0 + std::abs(c.p_w(k)));
    Vector3d a = c.p_w, b = c.p_w;
    a(k) += h;
    b(k) -= h;
    J.col(k) = (residual(c, c.T_w_c, a) - residual(c, c.T_w_c, b)) / (2.0 * h);
  }
  return J;
}

Matrix26 numericCameraJacobian(const Case& c) {
  Matrix26 J;
  for (int k = 0; k < 6; ++k) {
    const double h = 1e-6;
    const Vector6d e = Vector6d::Unit(k) * h;
    J.col(k) =
        (residual(c, c.T_w_c * geo::expSE3(e), c.p_w) - residual(c, c.T_w_c * geo::expSE3(-e), c.p_w)) / (2.0 * h);
  }
  return J;
}

// Relative tolerance of a central difference on these magnitudes (J ~ 100 px/unit).
template <typename A, typename B>
void expectClose(const A& analytic, const B& numeric, double rel, const std::string& what) {
  const double scale = 1.0 + numeric.cwiseAbs().maxCoeff();
  EXPECT_LT((analytic - numeric).cwiseAbs().maxCoeff(), rel * scale) << what << "\nanalytic\n"
                                                                     << analytic << "\nnumeric\n"
                                                                     << numeric;
}

struct Evaluated {
  opt::detail::ObsEval scalar;
  opt::detail::ObservationRows rows;
  double z = 0.0;
};

Evaluated evaluate(const Case& c) {
  Evaluated e;
  const Matrix3d R = c.T_w_c.linear();
  const Vector3d t = c.T_w_c.translation();
  EXPECT_TRUE(e.scalar.residual(c.K, kSigma2, R, t, c.p_w, c.uv));
  e.scalar.pointJacobian(R);
  const std::array<double, 12> q = opt::detail::packCamera(R, t);
  const double d0 = c.p_w.x() - q[9], d1 = c.p_w.y() - q[10], d2 = c.p_w.z() - q[11];
  e.z = q[6] * d0 + q[7] * d1 + q[8] * d2;
  const Eigen::Array2d fxy(c.K.fx, c.K.fy), cxy(c.K.cx, c.K.cy);
  e.rows.evaluate(q.data(), d0, d1, d2, e.z, c.uv.data(), fxy, cxy, kSigma2);
  return e;
}

}  // namespace

TEST(BaJacobians, ResidualCostAndWeightOfBothForms) {
  std::mt19937 rng(11);
  const geo::GemanMcClure kernel(std::sqrt(kSigma2));
  for (int trial = 0; trial < 200; ++trial) {
    const Case c = randomCase(rng);
    const Evaluated e = evaluate(c);
    const Vector2d r = residual(c, c.T_w_c, c.p_w);
    const double s = r.squaredNorm();
    EXPECT_NEAR(e.scalar.r0, r.x(), 1e-9);
    EXPECT_NEAR(e.scalar.r1, r.y(), 1e-9);
    EXPECT_NEAR(e.rows.r(0), r.x(), 1e-9);
    EXPECT_NEAR(e.rows.r(1), r.y(), 1e-9);
    EXPECT_NEAR(e.z, (c.T_w_c.inverse() * c.p_w).z(), 1e-9);
    EXPECT_NEAR(e.scalar.rho(kSigma2), kernel.rho(s), 1e-9 * (1.0 + s));
    EXPECT_NEAR(e.rows.rho, kernel.rho(s), 1e-9 * (1.0 + s));
    // The IRLS weight is d rho / d s (numerically, not by the kernel's own formula).
    const double h = 1e-6 * (1.0 + s);
    const double drho = (kernel.rho(s + h) - kernel.rho(s - h)) / (2.0 * h);
    EXPECT_NEAR(e.scalar.weight(kSigma2), drho, 1e-7);
    EXPECT_NEAR(e.rows.w, drho, 1e-7);
    EXPECT_GT(e.rows.w, 0.0);
    EXPECT_LE(e.rows.w, 1.0);
  }
}

TEST(BaJacobians, PointRowsMatchNumericDerivatives) {
  std::mt19937 rng(12);
  for (int trial = 0; trial < 200; ++trial) {
    const Case c = randomCase(rng);
    const Evaluated e = evaluate(c);
    const Matrix23 numeric = numericPointJacobian(c);
    Matrix23 scalar, rows, weighted;
    for (int k = 0; k < 3; ++k) {
      scalar(0, k) = e.scalar.jp0[k];
      scalar(1, k) = e.scalar.jp1[k];
    }
    rows.col(0) = e.rows.j0.matrix();
    rows.col(1) = e.rows.j1.matrix();
    rows.col(2) = e.rows.j2.matrix();
    weighted.col(0) = e.rows.wj0.matrix();
    weighted.col(1) = e.rows.wj1.matrix();
    weighted.col(2) = e.rows.wj2.matrix();
    expectClose(scalar, numeric, 1e-6, "ObsEval::pointJacobian, trial " + std::to_string(trial));
    expectClose(rows, numeric, 1e-6, "ObservationRows j0..j2, trial " + std::to_string(trial));
    expectClose(weighted, e.rows.w * numeric, 1e-6, "ObservationRows wj0..wj2, trial " + std::to_string(trial));
    expectClose(e.rows.wr.matrix(), e.rows.w * residual(c, c.T_w_c, c.p_w), 1e-9, "wr");
  }
}

TEST(BaJacobians, CameraRowsMatchNumericDerivatives) {
  std::mt19937 rng(13);
  for (int trial = 0; trial < 200; ++trial) {
    const Case c = randomCase(rng);
    const Evaluated e = evaluate(c);
    const Matrix26 numeric = numericCameraJacobian(c);
    // The two-wide form (linearize(): slots of free points).
    Matrix26 rows;
    e.rows.cameraColumns(e.z, rows.data());
    expectClose(rows, numeric, 1e-6, "ObservationRows::cameraColumns, trial " + std::to_string(trial));
    // The scalar form (free cameras observing fixed points) with its assembled blocks.
    opt::detail::Matrix6d Hcc = opt::detail::Matrix6d::Zero();
    opt::detail::Vector6d hdiag = opt::detail::Vector6d::Zero(), gc = opt::detail::Vector6d::Zero();
    Matrix26 Jc;
    Matrix23 Wjp;
    const double w = e.scalar.weight(kSigma2);
    e.scalar.addCamera(w, &Hcc, &hdiag, &gc, &Jc, &Wjp);
    expectClose(Jc, numeric, 1e-6, "ObsEval::addCamera rows, trial " + std::to_string(trial));
    expectClose(Wjp, w * numericPointJacobian(c), 1e-6, "ObsEval::addCamera Wjp");
    const opt::detail::Matrix6d H = (w * numeric.transpose() * numeric).eval();
    opt::detail::Matrix6d Hupper = Hcc;
    for (int col = 0; col < 6; ++col)
      for (int row = col + 1; row < 6; ++row) Hupper(row, col) = Hupper(col, row);  // only the upper part is summed
    expectClose(Hupper, H, 1e-6, "ObsEval::addCamera H_cc = w Jc^T Jc");
    // g = w Jc^T r is half the gradient of rho(|r|^2) in the camera's tangent space.
    opt::detail::Vector6d grad;
    for (int k = 0; k < 6; ++k) {
      const double h = 1e-6;
      const Vector6d d = Vector6d::Unit(k) * h;
      grad(k) = (robustCost(c, c.T_w_c * geo::expSE3(d), c.p_w) - robustCost(c, c.T_w_c * geo::expSE3(-d), c.p_w)) /
                (2.0 * h);
    }
    expectClose(gc, 0.5 * grad, 1e-5, "ObsEval::addCamera g_c = w Jc^T r, trial " + std::to_string(trial));
  }
}

TEST(BaJacobians, PointBlockIsWeightedGaussNewtonOfTheRobustCost) {
  // One point seen by three cameras: H = sum w Jp^T Jp and g = sum w Jp^T r, both
  // forms, with g half the numeric gradient of the summed robust cost.
  std::mt19937 rng(14);
  for (int trial = 0; trial < 100; ++trial) {
    Case base = randomCase(rng);
    std::vector<Case> views = {base};
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (int v = 0; v < 2; ++v) {
      Case c = base;
      c.T_w_c = base.T_w_c * geo::expSE3((Vector6d() << 0.3 * u(rng), 0.3 * u(rng), 0.2 * u(rng), 0.1 * u(rng),
                                          0.1 * u(rng), 0.1 * u(rng))
                                             .finished());
      c.uv = c.K.projectPoint(c.T_w_c.inverse() * c.p_w) + Vector2d(3.0 * u(rng), 3.0 * u(rng));
      views.push_back(c);
    }
    opt::detail::PointBlockRows block;
    Matrix3d H_scalar = Matrix3d::Zero();
    Eigen::Vector3d g_scalar = Eigen::Vector3d::Zero();
    Matrix3d H_numeric = Matrix3d::Zero();
    for (const Case& c : views) {
      Evaluated e = evaluate(c);
      block.add(e.rows);
      e.scalar.addPoint(e.scalar.weight(kSigma2), &H_scalar, &g_scalar);
      const Matrix23 J = numericPointJacobian(c);
      H_numeric += e.rows.w * J.transpose() * J;
    }
    for (int col = 0; col < 3; ++col)
      for (int row = col + 1; row < 3; ++row) H_scalar(row, col) = H_scalar(col, row);
    Matrix3d H_rows;
    Eigen::Vector3d g_rows;
    block.sum(&H_rows, &g_rows);
    Eigen::Vector3d grad;
    for (int k = 0; k < 3; ++k) {
      const double h = 1e-6 * (1.0 + std::abs(base.p_w(k)));
      Vector3d a = base.p_w, b = base.p_w;
      a(k) += h;
      b(k) -= h;
      double ca = 0.0, cb = 0.0;
      for (const Case& c : views) {
        ca += robustCost(c, c.T_w_c, a);
        cb += robustCost(c, c.T_w_c, b);
      }
      grad(k) = (ca - cb) / (2.0 * h);
    }
    expectClose(H_rows, H_numeric, 1e-6, "PointBlockRows H, trial " + std::to_string(trial));
    expectClose(H_scalar, H_numeric, 1e-6, "ObsEval::addPoint H, trial " + std::to_string(trial));
    expectClose(g_rows, 0.5 * grad, 1e-5, "PointBlockRows g, trial " + std::to_string(trial));
    expectClose(g_scalar, 0.5 * grad, 1e-5, "ObsEval::addPoint g, trial " + std::to_string(trial));
  }
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
