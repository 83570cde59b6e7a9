#include <gtest/gtest.h>

#include <algorithm>
#include <random>

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
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
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
  const double dir_err = std::acos(std::min(
      1.0, r.T_c1_c0.translation().normalized().dot(T_c1_c0.translation().normalized())));
  EXPECT_LT(dir_err * 180 / M_PI, 1.0);
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

TEST(TwoView, ConfigValidation) {
  TwoViewConfig cfg;
  cfg.min_points = 2;
  EXPECT_THROW(cfg.validate(), std::invalid_argument);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
