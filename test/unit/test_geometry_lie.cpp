// Lie-group math and projection Jacobians vs numeric differentiation.
#include <gtest/gtest.h>

#include <random>

#include "vitamin_e/geometry/lie.h"
#include "vitamin_e/geometry/projection.h"

using namespace vitamin_e::geometry;

namespace {
std::mt19937 rng(7);
Eigen::Vector3d randVec(double scale) {
  std::normal_distribution<double> g(0.0, scale);
  return Eigen::Vector3d(g(rng), g(rng), g(rng));
}
}  // namespace

TEST(Lie, So3ExpLogRoundTrip) {
  for (double scale : {1e-9, 1e-4, 0.3, 1.5}) {
    for (int k = 0; k < 20; ++k) {
      const Eigen::Vector3d phi = randVec(scale);
      if (phi.norm() >= M_PI) continue;
      const Eigen::Matrix3d R = expSO3(phi);
      EXPECT_NEAR((R.transpose() * R - Eigen::Matrix3d::Identity()).norm(), 0.0, 1e-12);
      EXPECT_NEAR(R.determinant(), 1.0, 1e-12);
      EXPECT_LT((logSO3(R) - phi).norm(), 1e-10 * (1.0 + phi.norm())) << phi.transpose();
    }
  }
  // Against Eigen's angle-axis, and near pi.
  const Eigen::Vector3d axis = Eigen::Vector3d(1, -2, 0.5).normalized();
  for (double angle : {0.1, 2.0, M_PI - 1e-6, M_PI - 1e-9}) {
    const Eigen::Matrix3d R = Eigen::AngleAxisd(angle, axis).toRotationMatrix();
    EXPECT_LT((expSO3(axis * angle) - R).norm(), 1e-12);
    EXPECT_LT((expSO3(logSO3(R)) - R).norm(), 1e-7) << angle;
  }
}

TEST(Lie, So3JacobiansMatchNumeric) {
  const double h = 1e-6;
  for (int k = 0; k < 10; ++k) {
    const Eigen::Vector3d phi = randVec(0.8);
    Eigen::Matrix3d Jr_num, Jl_num;
    for (int a = 0; a < 3; ++a) {
      const Eigen::Vector3d d = Eigen::Vector3d::Unit(a) * h;
      Jr_num.col(a) =
          (logSO3(expSO3(phi).transpose() * expSO3(phi + d)) - logSO3(expSO3(phi).transpose() * expSO3(phi - d))) /
          (2 * h);
      Jl_num.col(a) =
          (logSO3(expSO3(phi + d) * expSO3(phi).transpose()) - logSO3(expSO3(phi - d) * expSO3(phi).transpose())) /
          (2 * h);
    }
    EXPECT_LT((rightJacobianSO3(phi) - Jr_num).norm(), 1e-7);
    EXPECT_LT((leftJacobianSO3(phi) - Jl_num).norm(), 1e-7);
    EXPECT_LT((rightJacobianInvSO3(phi) * rightJacobianSO3(phi) - Eigen::Matrix3d::Identity()).norm(), 1e-10);
    EXPECT_LT((leftJacobianInvSO3(phi) * leftJacobianSO3(phi) - Eigen::Matrix3d::Identity()).norm(), 1e-10);
  }
}

TEST(Lie, Se3ExpLogRoundTrip) {
  for (int k = 0; k < 20; ++k) {
    Vector6d xi;
    xi.head<3>() = randVec(2.0);
    xi.tail<3>() = randVec(0.7);
    const Eigen::Isometry3d T = expSE3(xi);
    EXPECT_LT((logSE3(T) - xi).norm(), 1e-10);
    // exp of a pure translation is that translation.
    Vector6d tr = Vector6d::Zero();
    tr.head<3>() = xi.head<3>();
    EXPECT_LT((expSE3(tr).translation() - xi.head<3>()).norm(), 1e-14);
  }
  // Small-step derivative: d/dh exp(h xi) at 0 is the twist.
  Vector6d xi;
  xi << 0.1, -0.2, 0.3, 0.01, 0.02, -0.03;
  const Eigen::Isometry3d T = expSE3(1e-7 * xi);
  EXPECT_LT((T.translation() / 1e-7 - xi.head<3>()).norm(), 1e-6);
  EXPECT_LT((unskew(T.linear() - Eigen::Matrix3d::Identity()) / 1e-7 - xi.tail<3>()).norm(), 1e-6);
}

TEST(Projection, PinholeJacobianMatchesNumeric) {
  vitamin_e::camera::Pinhole K;
  K.fx = 450;
  K.fy = 460;
  K.cx = 320;
  K.cy = 240;
  const Eigen::Vector3d p(0.3, -0.4, 2.5);
  Matrix23d num;
  const double h = 1e-6;
  for (int a = 0; a < 3; ++a) {
    const Eigen::Vector3d d = Eigen::Vector3d::Unit(a) * h;
    num.col(a) = (K.projectPoint(p + d) - K.projectPoint(p - d)) / (2 * h);
  }
  EXPECT_LT((K.projectPointJacobian(p) - num).norm(), 1e-5);
}

TEST(Projection, ReprojectionJacobiansMatchNumeric) {
  vitamin_e::camera::Pinhole K;
  K.fx = 450;
  K.fy = 455;
  K.cx = 320;
  K.cy = 240;
  for (int k = 0; k < 10; ++k) {
    Eigen::Isometry3d T_w_c = Eigen::Isometry3d::Identity();
    T_w_c.linear() = expSO3(randVec(0.5));
    T_w_c.translation() = randVec(1.0);
    const Eigen::Vector3d p_w = T_w_c * Eigen::Vector3d(randVec(0.5) + Eigen::Vector3d(0, 0, 4));
    const Eigen::Vector2d uv(300, 200);
    auto residual = [&](const Eigen::Isometry3d& T, const Eigen::Vector3d& p) {
      return Eigen::Vector2d(uv - K.projectPoint(T.inverse() * p));
    };
    Matrix26d Jc;
    Matrix23d Jp;
    reprojectionJacobians(K, T_w_c.inverse() * p_w, T_w_c.linear(), &Jc, &Jp);
    const double h = 1e-6;
    Matrix26d Jc_num;
    for (int a = 0; a < 6; ++a) {
      const Vector6d d = Vector6d::Unit(a) * h;
      Jc_num.col(a) = (residual(T_w_c * expSE3(d), p_w) - residual(T_w_c * expSE3(-d), p_w)) / (2 * h);
    }
    Matrix23d Jp_num;
    for (int a = 0; a < 3; ++a) {
      const Eigen::Vector3d d = Eigen::Vector3d::Unit(a) * h;
      Jp_num.col(a) = (residual(T_w_c, p_w + d) - residual(T_w_c, p_w - d)) / (2 * h);
    }
    EXPECT_LT((Jc - Jc_num).norm(), 1e-4 * (1.0 + Jc.norm())) << "\n" << Jc << "\n" << Jc_num;
    EXPECT_LT((Jp - Jp_num).norm(), 1e-4 * (1.0 + Jp.norm()));
  }
}

TEST(Projection, GemanMcClureDerivatives) {
  const GemanMcClure k(2.0);
  for (double s : {0.5, 4.0, 30.0, 1e4}) {
    const double h = 1e-5 * s;
    EXPECT_NEAR(k.weight(s), (k.rho(s + h) - k.rho(s - h)) / (2 * h), 1e-6);
    EXPECT_NEAR(k.second(s), (k.weight(s + h) - k.weight(s - h)) / (2 * h), 1e-6);
    EXPECT_LE(k.rho(s), k.sigma2);
  }
  EXPECT_NEAR(k.weight(0.0), 1.0, 1e-15);
  EXPECT_NEAR(k.rho(1e-6), 1e-6, 1e-12);  // quadratic for small residuals
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
