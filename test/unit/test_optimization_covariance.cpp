// BaOptions::compute_covariance: the free cameras' 6x6 covariance after the
// points are eliminated, checked against (a) a dense reference built here from numerical
// Jacobians of every residual (all free cameras and points at once, no Schur complement) and
// (b) the spread of the solution over noise draws (Monte Carlo), which checks the scaling by
// the residual variance too.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstdio>
#include <random>

#include "vitamin_e/geometry/lie.h"
#include "vitamin_e/optimization/ba_synthetic.h"
#include "vitamin_e/optimization/subspace_gn.h"

using namespace vitamin_e::optimization;
namespace geo = vitamin_e::geometry;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

namespace {

SyntheticBa smallScene(int cams, int points, unsigned seed) {
  SyntheticBaConfig cfg;
  cfg.num_cameras = cams;
  cfg.num_points = points;
  cfg.noise_px = 0.0;
  cfg.outlier_ratio = 0.0;
  cfg.min_track = 2;
  cfg.max_track = cams;
  cfg.seed = seed;
  return makeSyntheticBa(cfg);
}

void addNoise(BaProblem* p, double sigma_px, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, sigma_px);
  for (auto& o : p->observations) o.uv += Eigen::Vector2d(n(rng), n(rng));
}

// Points seen by fewer than two cameras have no depth: fixed (as the SLAM does).
void fixUnconstrainedPoints(BaProblem* p) {
  std::vector<int> count(p->points.size(), 0);
  for (const auto& o : p->observations) ++count[o.point];
  for (size_t j = 0; j < p->points.size(); ++j) p->points[j].fixed = count[j] < 2;
}

// Dense reference: J of every residual w.r.t. every free variable by central differences
// (cameras: T * expSE3(delta), points: p + d), H = J^T W J with the Geman-McClure IRLS weights
// at the solution, cov = c (H^-1) camera blocks, c = sum |r|^2 / (2 m_in - n) over the m_in
// observations with |r| < 3 robust sigma. given_points: c (H_cc,i)^-1 of each camera's own
// block instead (the points held where they are).
std::vector<Matrix6d> referenceCovariance(const BaProblem& p, double robust_sigma, bool given_points = false) {
  std::vector<int> cam_col(p.cameras.size(), -1), pt_col(p.points.size(), -1);
  int n = 0;
  for (size_t c = 0; c < p.cameras.size(); ++c)
    if (!p.cameras[c].fixed) cam_col[c] = n, n += 6;
  std::vector<int> count(p.points.size(), 0);
  for (const auto& o : p.observations) ++count[o.point];
  for (size_t j = 0; j < p.points.size(); ++j)
    if (!p.points[j].fixed && count[j] > 0) pt_col[j] = n, n += 3;
  std::vector<int> active;
  for (size_t k = 0; k < p.observations.size(); ++k) {
    const auto& o = p.observations[k];
    if (cam_col[o.camera] >= 0 || pt_col[o.point] >= 0) active.push_back(static_cast<int>(k));
  }
  const int m = static_cast<int>(active.size());
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(2 * Eigen::Index{m}, n);
  Eigen::VectorXd w(2 * m);
  const double s2 = robust_sigma * robust_sigma;
  double sum_s = 0.0;
  int m_in = 0;
  const double h = 1e-6;
  for (int a = 0; a < m; ++a) {
    const BaObservation& o = p.observations[active[a]];
    Eigen::Vector2d r;
    EXPECT_TRUE(baResidual(p, o, &r));
    const double s = r.squaredNorm();
    const double wk = s2 * s2 / ((s2 + s) * (s2 + s));
    w(2 * Eigen::Index{a}) = w(2 * a + 1) = wk;
    if (s < 9.0 * s2) {
      sum_s += s;
      ++m_in;
    }
    BaProblem q = p;
    if (cam_col[o.camera] >= 0) {
      for (int d = 0; d < 6; ++d) {
        geo::Vector6d e = geo::Vector6d::Zero();
        e(d) = h;
        Eigen::Vector2d rp, rm;
        q.cameras[o.camera].T_w_c = p.cameras[o.camera].T_w_c * geo::expSE3(e);
        baResidual(q, o, &rp);
        q.cameras[o.camera].T_w_c = p.cameras[o.camera].T_w_c * geo::expSE3(-e);
        baResidual(q, o, &rm);
        J.block<2, 1>(2 * Eigen::Index{a}, cam_col[o.camera] + d) = (rp - rm) / (2 * h);
      }
      q.cameras[o.camera].T_w_c = p.cameras[o.camera].T_w_c;
    }
    if (pt_col[o.point] >= 0) {
      for (int d = 0; d < 3; ++d) {
        Eigen::Vector2d rp, rm;
        q.points[o.point].p_w = p.points[o.point].p_w + h * Eigen::Vector3d::Unit(d);
        baResidual(q, o, &rp);
        q.points[o.point].p_w = p.points[o.point].p_w - h * Eigen::Vector3d::Unit(d);
        baResidual(q, o, &rm);
        J.block<2, 1>(2 * Eigen::Index{a}, pt_col[o.point] + d) = (rp - rm) / (2 * h);
      }
    }
  }
  const Eigen::MatrixXd H = J.transpose() * w.asDiagonal() * J;
  const Eigen::MatrixXd H_inv = H.ldlt().solve(Eigen::MatrixXd::Identity(n, n));
  const double sigma2 = sum_s / (2 * m_in - n);
  std::vector<Matrix6d> cov(p.cameras.size(), Matrix6d::Zero());
  for (size_t c = 0; c < p.cameras.size(); ++c) {
    if (cam_col[c] < 0) continue;
    const Matrix6d H_cc = H.block<6, 6>(cam_col[c], cam_col[c]);
    cov[c] = sigma2 * (given_points ? Matrix6d(H_cc.inverse()) : Matrix6d(H_inv.block<6, 6>(cam_col[c], cam_col[c])));
  }
  return cov;
}

}  // namespace

TEST(BaCovariance, MatchesADenseNumericalReference) {
  using Covariance = BaOptions::Covariance;
  for (const auto& [schur, of] :
       {std::pair{true, Covariance::kWithPoints}, std::pair{false, Covariance::kWithPoints},
        std::pair{true, Covariance::kGivenPoints}, std::pair{false, Covariance::kGivenPoints}}) {
    const bool given = of == Covariance::kGivenPoints;
    SyntheticBa s = smallScene(5, 80, 4);
    BaProblem p = s.truth;
    p.cameras[0].fixed = p.cameras[1].fixed = true;
    fixUnconstrainedPoints(&p);
    addNoise(&p, 0.7, 21);
    // One gross outlier: its weight is tiny in the solver and in the reference alike.
    p.observations[3].uv += Eigen::Vector2d(25.0, -30.0);
    BaOptions opt;
    opt.use_schur = schur;
    opt.max_sweeps = 100;
    opt.tolerance = 1e-14;
    opt.compute_covariance = true;
    opt.covariance = of;
    const BaSummary sum = solveSubspaceGaussNewton(p, opt);
    ASSERT_EQ(sum.camera_covariance.size(), p.cameras.size());
    const auto ref = referenceCovariance(p, opt.robust_sigma_px, given);
    EXPECT_GT(sum.residual_variance, 0.25) << "0.7 px noise per coordinate: 0.49 px^2";
    EXPECT_LT(sum.residual_variance, 0.75);
    for (size_t c = 0; c < p.cameras.size(); ++c) {
      if (p.cameras[c].fixed) {
        EXPECT_FALSE(sum.camera_covariance_valid[c]);
        EXPECT_EQ(sum.camera_covariance[c].norm(), 0.0);
        continue;
      }
      const char* what =
          given ? (schur ? " (given points, Schur)" : " (given points, plain)") : (schur ? " (Schur)" : " (plain)");
      ASSERT_TRUE(sum.camera_covariance_valid[c]) << "camera " << c << what;
      const Matrix6d& C = sum.camera_covariance[c];
      EXPECT_LT((C - ref[c]).norm(), 1e-4 * ref[c].norm()) << "camera " << c << what << "\nsolver:\n"
                                                           << C << "\nreference:\n"
                                                           << ref[c];
      EXPECT_GT(Eigen::SelfAdjointEigenSolver<Matrix6d>(C).eigenvalues().minCoeff(), 0.0);
    }
  }
}

// The per-frame BA's shape: fixed keyframes, one free camera, free points (2 to 5
// observations each), 1 px noise under Geman-McClure at 2 px, without and with 5 % gross
// outliers. Over 300 independent noise draws the solution's error delta = log(T_true^-1 T_est)
// spreads as predicted: the mean Mahalanobis norm delta^T C^-1 delta is 6 for a right
// covariance (chi-square with 6 dof; over 300 draws its standard deviation is 0.2), and the
// empirical covariance's trace matches the predicted one; both within 30 %. (The IRLS-weighted
// residual variance instead of the inliers' plain one gives about 2.5x too small a covariance
// here: a Mahalanobis mean near 15.)
TEST(BaCovariance, PredictsTheSpreadOfTheSolutionOverNoise) {
  SyntheticBa s = smallScene(5, 120, 9);
  const int free_cam = 4;
  const int draws = 300;
  for (double outliers : {0.0, 0.05}) {
    double mahalanobis = 0.0;
    Matrix6d empirical = Matrix6d::Zero(), predicted = Matrix6d::Zero();
    for (int d = 0; d < draws; ++d) {
      BaProblem p = s.truth;
      for (int c = 0; c < free_cam; ++c) p.cameras[c].fixed = true;
      fixUnconstrainedPoints(&p);
      addNoise(&p, 1.0, 1000 + d);
      std::mt19937 rng(77 + d);
      std::uniform_real_distribution<double> u(0.0, 1.0);
      for (auto& o : p.observations) {
        if (u(rng) < outliers) o.uv += Eigen::Vector2d(10.0 + 20.0 * u(rng), -10.0 - 20.0 * u(rng));
      }
      BaOptions opt;
      opt.max_sweeps = 30;
      opt.tolerance = 1e-12;
      opt.compute_covariance = true;
      opt.covariance = BaOptions::Covariance::kWithPoints;  // the pose's spread, the points' error included
      const BaSummary sum = solveSubspaceGaussNewton(p, opt);
      ASSERT_TRUE(sum.camera_covariance_valid[free_cam]);
      const Matrix6d& C = sum.camera_covariance[free_cam];
      const geo::Vector6d delta = geo::logSE3(s.truth.cameras[free_cam].T_w_c.inverse() * p.cameras[free_cam].T_w_c);
      mahalanobis += delta.dot(C.ldlt().solve(delta));
      empirical += delta * delta.transpose();
      predicted += C;
    }
    mahalanobis /= draws;
    empirical /= draws;
    predicted /= draws;
    std::printf("outliers %.2f: mean Mahalanobis %.2f (6 expected), empirical/predicted trace %.2f\n", outliers,
                mahalanobis, empirical.trace() / predicted.trace());
    EXPECT_NEAR(mahalanobis, 6.0, 0.3 * 6.0) << "outliers " << outliers;
    EXPECT_NEAR(empirical.trace() / predicted.trace(), 1.0, 0.3) << "outliers " << outliers << "\nempirical:\n"
                                                                 << empirical << "\npredicted:\n"
                                                                 << predicted;
  }
}

TEST(BaCovariance, OffByDefaultAndInvalidWithoutAGauge) {
  SyntheticBa s = smallScene(4, 60, 5);
  BaProblem p = s.truth;
  p.cameras[0].fixed = p.cameras[1].fixed = true;
  addNoise(&p, 0.5, 3);
  BaProblem q = p;
  const BaSummary off = solveSubspaceGaussNewton(p, BaOptions());
  EXPECT_TRUE(off.camera_covariance.empty());
  EXPECT_EQ(off.residual_variance, 0.0);
  // The option changes nothing of the solve itself.
  BaOptions on;
  on.compute_covariance = true;
  const BaSummary with = solveSubspaceGaussNewton(q, on);
  EXPECT_EQ(with.final_cost, off.final_cost);
  for (size_t c = 0; c < p.cameras.size(); ++c) EXPECT_TRUE(p.cameras[c].T_w_c.isApprox(q.cameras[c].T_w_c, 0.0));
  // No fixed camera: the 7-DoF gauge leaves S singular, so no covariance is claimed.
  on.covariance = BaOptions::Covariance::kWithPoints;
  BaProblem g = s.truth;
  addNoise(&g, 0.5, 4);
  const BaSummary gauge = solveSubspaceGaussNewton(g, on);
  for (size_t c = 0; c < g.cameras.size(); ++c) EXPECT_FALSE(gauge.camera_covariance_valid[c]);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
