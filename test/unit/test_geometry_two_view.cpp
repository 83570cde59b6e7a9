#include <gtest/gtest.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

#include "../../src/geometry/two_view_detail.h"
#include "vitamin_e/geometry/lie.h"
#include "vitamin_e/geometry/two_view.h"

using namespace vitamin_e::geometry;

namespace {

// Points in front of camera 0; camera 1 = T_c1_c0 applied to them.
void makeScene(const Eigen::Isometry3d& T_c1_c0, int n, double noise_px, double outliers, unsigned seed,
               std::vector<Eigen::Vector2d>* xy0, std::vector<Eigen::Vector2d>* xy1,
               std::vector<Eigen::Vector3d>* pts) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::normal_distribution<double> g(0.0, noise_px / 450.0);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d p(u(rng) * 2.0, u(rng) * 1.5, 5.0 + 2.0 * u(rng));
    const Eigen::Vector3d q = T_c1_c0 * p;
    pts->push_back(p);
    xy0->push_back(p.head<2>() / p.z() + Eigen::Vector2d(g(rng), g(rng)));
    Eigen::Vector2d x1 = q.head<2>() / q.z() + Eigen::Vector2d(g(rng), g(rng));
    if (i < outliers * n) x1 += Eigen::Vector2d(0.05 * u(rng), 0.05 + 0.05 * std::abs(u(rng)));
    xy1->push_back(x1);
  }
}

double median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

// A textured wall seen head-on while the camera slides sideways (with a little yaw): every
// point on one plane, the field of view of the 376x240 EuRoC camera (+-0.8 x +-0.5).
// The essential matrix of a plane is not unique: besides the true motion, a 'twisted' one
// (moving towards the wall) explains every correspondence. Returns the true T_c1_c0.
Eigen::Isometry3d makeWall(double baseline, double yaw, double noise_px, unsigned seed,
                           std::vector<Eigen::Vector2d>* xy0, std::vector<Eigen::Vector2d>* xy1) {
  const double half_fov_x = 0.8, half_fov_y = 0.5;
  Eigen::Isometry3d T_c1_c0 = Eigen::Isometry3d::Identity();
  T_c1_c0.linear() = expSO3(Eigen::Vector3d(0.0, yaw, 0.0));
  T_c1_c0.translation() = -T_c1_c0.linear() * Eigen::Vector3d(baseline, 0.02 * baseline, 0.0);
  // The wall: z = 2 m at the centre, tilted 0.15 rad about x (the camera looks slightly down).
  const Eigen::Vector3d normal = expSO3(Eigen::Vector3d(0.15, 0.0, 0.0)) * Eigen::Vector3d::UnitZ();
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> ux(-half_fov_x, half_fov_x), uy(-half_fov_y, half_fov_y);
  std::normal_distribution<double> g(0.0, noise_px / 229.0);
  while (xy0->size() < 800) {
    const Eigen::Vector3d ray(ux(rng), uy(rng), 1.0);
    const Eigen::Vector3d p = ray * (2.0 / normal.dot(ray));
    const Eigen::Vector3d q = T_c1_c0 * p;
    const Eigen::Vector2d x1 = q.head<2>() / q.z();
    if (q.z() <= 0.0 || std::abs(x1.x()) > half_fov_x || std::abs(x1.y()) > half_fov_y) continue;
    xy0->push_back(p.head<2>() / p.z() + Eigen::Vector2d(g(rng), g(rng)));
    xy1->push_back(x1 + Eigen::Vector2d(g(rng), g(rng)));
  }
  return T_c1_c0;
}

// A relative pose (R, unit t; E = [t]x R) and a correspondence of a point 2-8 units in front of
// camera 0, x1 a few pixels off the epipolar-consistent position unless noise_px is 0.
struct EpipolarCase {
  Eigen::Matrix3d R;
  Eigen::Vector3d t, x0, x1;
};

EpipolarCase randomEpipolarCase(std::mt19937& rng, double noise_px) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  EpipolarCase c;
  c.R = expSO3(0.5 * Eigen::Vector3d(u(rng), u(rng), u(rng)));
  c.t = Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized();
  for (;;) {
    c.x0 = Eigen::Vector3d(0.8 * u(rng), 0.5 * u(rng), 1.0);
    const Eigen::Vector3d q = c.R * (c.x0 * (5.0 + 3.0 * u(rng))) + c.t;
    if (q.z() < 0.5) continue;
    c.x1 = (q / q.z() + noise_px / 450.0 * Eigen::Vector3d(u(rng), u(rng), 0.0));
    return c;
  }
}

// The pose after the refinement's update with step delta = (w, d).
void retract(const EpipolarCase& c, const Eigen::Matrix<double, 3, 2>& B, const Eigen::Matrix<double, 5, 1>& delta,
             Eigen::Matrix3d* R, Eigen::Vector3d* t) {
  *R = c.R * expSO3(delta.head<3>());
  *t = (c.t + B * delta.tail<2>()).normalized();
}

// Central differences of residual(R, t) in the refinement's 5 DoF.
template <typename F>
Eigen::Matrix<double, 1, 5> numericJacobian(const EpipolarCase& c, const Eigen::Matrix<double, 3, 2>& B,
                                            const F& residual) {
  Eigen::Matrix<double, 1, 5> J;
  for (int k = 0; k < 5; ++k) {
    const double h = 1e-6;
    const Eigen::Matrix<double, 5, 1> e = Eigen::Matrix<double, 5, 1>::Unit(k) * h;
    Eigen::Matrix3d Ra, Rb;
    Eigen::Vector3d ta, tb;
    retract(c, B, e, &Ra, &ta);
    retract(c, B, -e, &Rb, &tb);
    J(k) = (residual(Ra, ta) - residual(Rb, tb)) / (2.0 * h);
  }
  return J;
}

}  // namespace

TEST(TwoView, RecoversRelativePoseUpToScale) {
  Eigen::Isometry3d T_c1_c0 = Eigen::Isometry3d::Identity();
  T_c1_c0.linear() = expSO3(Eigen::Vector3d(0.02, -0.08, 0.01));
  T_c1_c0.translation() = Eigen::Vector3d(-0.5, 0.05, 0.1);
  std::vector<Eigen::Vector2d> xy0, xy1;
  std::vector<Eigen::Vector3d> pts;
  makeScene(T_c1_c0, 300, 0.5, 0.1, 4, &xy0, &xy1, &pts);
  TwoViewConfig cfg;
  const TwoViewResult r = initializeTwoView(xy0, xy1, cfg);
  ASSERT_TRUE(r.ok) << r.reason;
  EXPECT_LT(rotationAngle(r.T_c1_c0.linear(), T_c1_c0.linear()) * 180 / M_PI, 0.1);
  const double dir_err =
      std::acos(std::min(1.0, r.T_c1_c0.translation().normalized().dot(T_c1_c0.translation().normalized())));
  EXPECT_LT(dir_err * 180 / M_PI, 0.35);  // the refined direction (measured 0.23 deg)
  EXPECT_GT(r.median_parallax_deg, cfg.min_parallax_deg);
  EXPECT_GE(r.num_inliers, 250);
  // Scale convention: median depth of the valid points is 1; points match truth up to scale.
  std::vector<double> depth, rel;
  const double scale = T_c1_c0.translation().norm() / r.T_c1_c0.translation().norm();
  int outliers_valid = 0;
  for (size_t i = 0; i < pts.size(); ++i) {
    if (!r.valid[i]) continue;
    if (i < 30) ++outliers_valid;
    depth.push_back(r.points_c0[i].z());
    // 0.5 px noise, ~5 deg parallax: depth sigma ~ z^2 * 0.5 / (450 * 0.5) ~ 3% at 7 m.
    EXPECT_LT((r.points_c0[i] * scale - pts[i]).norm(), 0.15 * pts[i].z()) << i;
    rel.push_back((r.points_c0[i] * scale - pts[i]).norm() / pts[i].z());
  }
  EXPECT_LT(median(rel), 0.02);
  EXPECT_NEAR(median(depth), 1.0, 1e-9);
  EXPECT_LE(outliers_valid, 2);
}

TEST(TwoView, RefusesPureRotation) {
  Eigen::Isometry3d T_c1_c0 = Eigen::Isometry3d::Identity();
  T_c1_c0.linear() = expSO3(Eigen::Vector3d(0.03, -0.1, 0.02));
  std::vector<Eigen::Vector2d> xy0, xy1;
  std::vector<Eigen::Vector3d> pts;
  makeScene(T_c1_c0, 300, 0.5, 0.0, 5, &xy0, &xy1, &pts);
  const TwoViewResult r = initializeTwoView(xy0, xy1, TwoViewConfig());
  EXPECT_FALSE(r.ok);
  EXPECT_FALSE(r.reason.empty());
  for (bool v : r.valid) EXPECT_FALSE(v && r.ok);
}

TEST(TwoView, RefusesTinyBaseline) {
  Eigen::Isometry3d T_c1_c0 = Eigen::Isometry3d::Identity();
  T_c1_c0.linear() = expSO3(Eigen::Vector3d(0.0, -0.05, 0.0));
  T_c1_c0.translation() = Eigen::Vector3d(-0.02, 0.0, 0.0);  // ~0.2 deg parallax at 5 m
  std::vector<Eigen::Vector2d> xy0, xy1;
  std::vector<Eigen::Vector3d> pts;
  makeScene(T_c1_c0, 300, 0.3, 0.0, 6, &xy0, &xy1, &pts);
  const TwoViewResult r = initializeTwoView(xy0, xy1, TwoViewConfig());
  EXPECT_FALSE(r.ok);
  EXPECT_FALSE(r.reason.empty());
}

// A plane: the motion must be the true one, with every point in front of both cameras, or
// there must be no result at all; never the twisted motion (a map from it tracks on, with
// errors that grow to metres). Baselines from 4 to 30 cm at 2 m (1.2 to 9 degrees), 0.3 px
// noise (the tracker's), several noise draws: the five-point RANSAC returned the twisted
// motion in some of these before the homography candidates were added.
TEST(TwoView, PlanarSceneGivesTheTrueMotionNotTheTwistedOne) {
  TwoViewConfig cfg;
  cfg.focal_px = 229.0;
  int ok = 0, cases = 0;
  for (const double baseline : {0.04, 0.06, 0.1, 0.15, 0.2, 0.3}) {
    for (const unsigned seed : {1u, 2u, 3u}) {
      std::vector<Eigen::Vector2d> xy0, xy1;
      const Eigen::Isometry3d T_c1_c0 = makeWall(baseline, 0.01 * seed - 0.02, 0.3, seed, &xy0, &xy1);
      const TwoViewResult r = initializeTwoView(xy0, xy1, cfg);
      ++cases;
      if (!r.ok) continue;
      ++ok;
      const double dir_deg =
          std::acos(std::min(1.0, r.T_c1_c0.translation().normalized().dot(T_c1_c0.translation().normalized()))) * 180 /
          M_PI;
      EXPECT_LT(rotationAngle(r.T_c1_c0.linear(), T_c1_c0.linear()) * 180 / M_PI, 0.3)
          << "baseline " << baseline << " seed " << seed;
      EXPECT_LT(dir_deg, 5.0) << "baseline " << baseline << " seed " << seed;
      EXPECT_GE(r.num_inliers, 0.95 * xy0.size()) << "baseline " << baseline << " seed " << seed;
    }
  }
  // From 6 cm (1.7 degrees of parallax) on, every case initializes.
  EXPECT_GE(ok, cases - 3);
}

// Fewer than min_valid_ratio of the inliers in front of both cameras: refused.
TEST(TwoView, RefusesWhenFewPointsAreInFrontOfBothCameras) {
  std::vector<Eigen::Vector2d> xy0, xy1;
  makeWall(0.2, 0.0, 0.3, 1, &xy0, &xy1);
  TwoViewConfig cfg;
  cfg.focal_px = 229.0;
  const TwoViewResult all = initializeTwoView(xy0, xy1, cfg);
  ASSERT_TRUE(all.ok) << all.reason;
  // A reprojection bound under the 0.3 px noise leaves only some inliers valid: asserted, so
  // that the refusal below is tested and not skipped.
  cfg.max_reproj_error_px = 0.15;
  const TwoViewResult few = initializeTwoView(xy0, xy1, cfg);
  ASSERT_GE(few.num_inliers, cfg.min_points);
  ASSERT_LT(few.num_inliers, cfg.min_valid_ratio * few.num_essential_inliers);
  EXPECT_FALSE(few.ok);
  EXPECT_NE(few.reason.find("in front of both cameras"), std::string::npos) << few.reason;
  // The same run with the ratio check off initializes.
  cfg.min_valid_ratio = 0.0;
  const TwoViewResult lax = initializeTwoView(xy0, xy1, cfg);
  EXPECT_TRUE(lax.ok) << lax.reason;
}

// The refinement's Gauss-Newton rows (detail::sampsonJacobian, denominator frozen) against central
// differences of the epipolar residual computed here, at random poses and correspondences a few
// pixels off (residuals of both signs). A slightly wrong row only slows the refinement (it keeps the
// pose when a step does not lower the cost), which the tests of initializeTwoView do not notice.
TEST(TwoViewRefinement, SampsonJacobianMatchesCentralDifferences) {
  const double focal = 450.0;
  std::mt19937 rng(21);
  for (int trial = 0; trial < 200; ++trial) {
    const EpipolarCase c = randomEpipolarCase(rng, 3.0);
    const Eigen::Matrix3d E = skew(c.t) * c.R;
    const Eigen::Vector3d Ex0 = E * c.x0, Etx1 = E.transpose() * c.x1;
    const double denom_ref = std::sqrt(Ex0.head<2>().squaredNorm() + Etx1.head<2>().squaredNorm());
    double denom;
    const double r = detail::sampson(E, c.x0, c.x1, &denom);
    ASSERT_NEAR(denom, denom_ref, 1e-12 * denom_ref);
    ASSERT_NEAR(r, c.x1.dot(Ex0) / denom_ref, 1e-12);

    // The update's basis spans the tangent plane of the unit sphere at t.
    const Eigen::Matrix<double, 3, 2> B = detail::tangentBasis(c.t);
    EXPECT_LT((B.transpose() * B - Eigen::Matrix2d::Identity()).norm(), 1e-12);
    EXPECT_LT((B.transpose() * c.t).norm(), 1e-12);

    const double s = focal / denom;
    const Eigen::Matrix<double, 1, 5> analytic = detail::sampsonJacobian(c.R, c.t, B, c.x0, c.x1, s);
    const Eigen::Matrix<double, 1, 5> numeric = numericJacobian(
        c, B, [&](const Eigen::Matrix3d& R, const Eigen::Vector3d& t) { return s * c.x1.dot(skew(t) * R * c.x0); });
    EXPECT_LT((analytic - numeric).norm(), 1e-6 * numeric.norm())
        << "trial " << trial << "\nanalytic " << analytic << "\nnumeric  " << numeric;
  }
}

// On exact correspondences the residual is zero, so the frozen denominator's derivative drops out:
// the rows are the Jacobian of the Sampson distance itself, so near the solution the refinement
// takes Gauss-Newton steps on the cost it reports.
TEST(TwoViewRefinement, SampsonJacobianIsTheFullDerivativeAtExactCorrespondences) {
  const double focal = 450.0;
  std::mt19937 rng(22);
  for (int trial = 0; trial < 200; ++trial) {
    const EpipolarCase c = randomEpipolarCase(rng, 0.0);
    double denom;
    const double r = detail::sampson(skew(c.t) * c.R, c.x0, c.x1, &denom);
    ASSERT_LT(std::abs(focal * r), 1e-9);
    const Eigen::Matrix<double, 3, 2> B = detail::tangentBasis(c.t);
    const Eigen::Matrix<double, 1, 5> analytic = detail::sampsonJacobian(c.R, c.t, B, c.x0, c.x1, focal / denom);
    const Eigen::Matrix<double, 1, 5> numeric =
        numericJacobian(c, B, [&](const Eigen::Matrix3d& R, const Eigen::Vector3d& t) {
          double d;
          return focal * detail::sampson(skew(t) * R, c.x0, c.x1, &d);
        });
    EXPECT_LT((analytic - numeric).norm(), 1e-6 * numeric.norm())
        << "trial " << trial << "\nanalytic " << analytic << "\nnumeric  " << numeric;
  }
}

// The pose chosen from an essential matrix is cv::recoverPose's (the reference it replaces):
// the same decomposition, and on inliers away from the depth limits the same count.
TEST(TwoViewEssential, PoseFromEssentialIsRecoverPosesChoice) {
  const double deg = M_PI / 180.0;
  const Eigen::Isometry3d motions[] = {
      Eigen::Translation3d(0.4, 0.05, 0.1) * Eigen::AngleAxisd(3 * deg, Eigen::Vector3d::UnitY()),
      Eigen::Translation3d(-0.1, 0.02, -0.8) * Eigen::AngleAxisd(-6 * deg, Eigen::Vector3d::UnitY()),  // forward
      Eigen::Translation3d(0.05, -0.3, 0.2) * Eigen::AngleAxisd(10 * deg, Eigen::Vector3d(1, 2, 3).normalized()),
  };
  unsigned seed = 7;
  for (const Eigen::Isometry3d& T_c1_c0 : motions) {
    std::vector<Eigen::Vector2d> xy0, xy1;
    std::vector<Eigen::Vector3d> pts;
    makeScene(T_c1_c0, 300, 0.5, 0.2, seed++, &xy0, &xy1, &pts);
    const Eigen::Vector3d t_true = T_c1_c0.translation().normalized();
    const Eigen::Matrix3d E = skew(t_true) * T_c1_c0.linear();
    std::vector<bool> in(xy0.size(), true);
    cv::Mat mask(static_cast<int>(xy0.size()), 1, CV_8U, cv::Scalar(1));
    std::vector<cv::Point2d> p0, p1;
    for (size_t i = 0; i < xy0.size(); ++i) {
      p0.emplace_back(xy0[i].x(), xy0[i].y());
      p1.emplace_back(xy1[i].x(), xy1[i].y());
      if (i < xy0.size() / 5) in[i] = false, mask.at<std::uint8_t>(static_cast<int>(i)) = 0;  // makeScene's outliers
    }
    cv::Mat Ecv, Rcv, tcv;
    cv::eigen2cv(E, Ecv);
    const int cv_good = cv::recoverPose(Ecv, p0, p1, cv::Mat::eye(3, 3, CV_64F), Rcv, tcv, mask);
    Eigen::Matrix3d R_cv;
    Eigen::Vector3d t_cv;
    cv::cv2eigen(Rcv, R_cv);
    cv::cv2eigen(tcv, t_cv);

    Eigen::Matrix3d R;
    Eigen::Vector3d t;
    const int good = detail::poseFromEssential(E, xy0, xy1, in, 50.0, &R, &t);
    EXPECT_EQ(good, cv_good);
    EXPECT_EQ(good, 240);  // every inlier lies in front of both cameras
    EXPECT_LT((R - R_cv).norm(), 1e-9);
    EXPECT_LT((t - t_cv).norm(), 1e-9);
    EXPECT_LT((R - T_c1_c0.linear()).norm(), 1e-9);
    EXPECT_LT((t - t_true).norm(), 1e-9);
  }
}

TEST(TwoViewEssential, PoseFromEssentialRefusesADegenerateMatrix) {
  const std::vector<Eigen::Vector2d> xy(10, Eigen::Vector2d(0.1, 0.2));
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::UnitX();
  Eigen::Matrix3d E = Eigen::Matrix3d::Zero();
  E(0, 0) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(detail::poseFromEssential(E, xy, xy, {}, 50.0, &R, &t), 0);
  EXPECT_EQ(detail::poseFromEssential(Eigen::Matrix3d::Zero(), xy, xy, {}, 50.0, &R, &t), 0);
  EXPECT_EQ(R, Eigen::Matrix3d::Identity());
  EXPECT_EQ(t, Eigen::Vector3d::UnitX());
}

TEST(TwoView, ConfigValidation) {
  TwoViewConfig cfg;
  cfg.min_points = 2;
  EXPECT_THROW(cfg.validate(), std::invalid_argument);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
