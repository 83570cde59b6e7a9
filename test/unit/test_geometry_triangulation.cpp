#include <gtest/gtest.h>

#include "vitamin_e/geometry/lie.h"
#include "vitamin_e/geometry/triangulation.h"

using namespace vitamin_e::geometry;

namespace {
Eigen::Isometry3d pose(const Eigen::Vector3d& t, const Eigen::Vector3d& rot) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = expSO3(rot);
  T.translation() = t;
  return T;
}
Eigen::Vector2d observe(const Eigen::Isometry3d& T_w_c, const Eigen::Vector3d& p_w) {
  const Eigen::Vector3d p = T_w_c.inverse() * p_w;
  return p.head<2>() / p.z();
}
}  // namespace

TEST(Triangulation, RecoversKnownPointFromThreeViews) {
  const Eigen::Vector3d p_w(0.4, -0.3, 5.0);
  const std::vector<Eigen::Isometry3d> T = {pose({0, 0, 0}, {0, 0, 0}), pose({0.5, 0, 0.1}, {0.01, -0.05, 0}),
                                            pose({1.0, 0.1, 0}, {0, -0.1, 0.02})};
  std::vector<Eigen::Vector2d> xy;
  xy.reserve(T.size());
  for (const auto& t : T) xy.push_back(observe(t, p_w));
  TriangulationConfig cfg;
  const TriangulationResult r = triangulatePoint(T, xy, cfg);
  ASSERT_TRUE(r.ok) << r.reason;
  EXPECT_LT((r.p_w - p_w).norm(), 1e-9);
  ASSERT_EQ(r.reproj_error_px.size(), 3u);
  for (double e : r.reproj_error_px) EXPECT_LT(e, 1e-6);
  const double expected = parallaxDeg(T[0].translation(), T[2].translation(), p_w);
  EXPECT_NEAR(r.parallax_deg, expected, 1e-9);
  EXPECT_GT(r.parallax_deg, 10.0);

  // Noisy observations: GN refines the DLT, small error.
  std::vector<Eigen::Vector2d> noisy = xy;
  noisy[0] += Eigen::Vector2d(1.0, -0.5) / 450.0;
  noisy[1] += Eigen::Vector2d(-0.7, 0.8) / 450.0;
  const TriangulationResult rn = triangulatePoint(T, noisy, cfg);
  ASSERT_TRUE(rn.ok) << rn.reason;
  // ~1 px noise at 5 m depth with a 1 m baseline: depth sigma ~ 25 / 450 = 0.06 m.
  EXPECT_LT((rn.p_w - p_w).norm(), 0.2);
  EXPECT_GT((rn.p_w - p_w).norm(), 1e-6);
}

TEST(Triangulation, RejectsSmallParallaxAndPointsBehind) {
  const Eigen::Vector3d p_w(0.2, 0.1, 20.0);
  const std::vector<Eigen::Isometry3d> T = {pose({0, 0, 0}, {0, 0, 0}), pose({0.05, 0, 0}, {0, 0, 0})};
  TriangulationConfig cfg;
  const TriangulationResult r = triangulatePoint(T, {observe(T[0], p_w), observe(T[1], p_w)}, cfg);
  EXPECT_FALSE(r.ok);
  EXPECT_LT(r.parallax_deg, 1.0);
  EXPECT_EQ(r.failed, TriangulationCheck::kParallax) << r.reason;

  // Rays that meet behind the cameras.
  const std::vector<Eigen::Isometry3d> T2 = {pose({0, 0, 0}, {0, 0, 0}), pose({1.0, 0, 0}, {0, 0, 0})};
  const TriangulationResult rb = triangulatePoint(T2, {Eigen::Vector2d(0.1, 0.0), Eigen::Vector2d(0.3, 0.0)}, cfg);
  EXPECT_FALSE(rb.ok);
  EXPECT_FALSE(rb.cheirality_ok);
  EXPECT_EQ(rb.failed, TriangulationCheck::kCheirality) << rb.reason;
}

TEST(Triangulation, ConfigValidation) {
  TriangulationConfig cfg;
  cfg.focal_px = 0.0;
  EXPECT_THROW(cfg.validate(), std::invalid_argument);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
