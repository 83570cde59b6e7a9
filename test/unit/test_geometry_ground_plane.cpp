// The road plane under a level camera (geometry::fitGroundPlane): found among
// facades and a raised sidewalk, its height to the camera measured, and refused
// when the points do not show a road.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Geometry>

#include "vitamin_e/geometry/ground_plane.h"

using vitamin_e::geometry::fitGroundPlane;
using vitamin_e::geometry::GroundPlaneConfig;

namespace {

// A street seen from a camera `height` above the road (camera frame: x right,
// y down, z forward), pitched down by pitch_deg: road points ahead, facades on
// both sides, a sidewalk 0.15 x height higher on the right; noise in depth.
std::vector<Eigen::Vector3d> street(double height, double pitch_deg, int road, int facade, int sidewalk,
                                    double noise = 0.0) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> n(0.0, 1.0);
  std::vector<Eigen::Vector3d> pts;
  const double a = pitch_deg * M_PI / 180.0;
  // level frame -> pitched camera frame (a rotation about x)
  const Eigen::Matrix3d R_c_l = Eigen::AngleAxisd(-a, Eigen::Vector3d::UnitX()).toRotationMatrix();
  auto add = [&](const Eigen::Vector3d& p_l) {
    Eigen::Vector3d p = R_c_l * p_l;
    p *= 1.0 + noise * n(rng);  // along the ray: a depth error
    pts.push_back(p);
  };
  for (int i = 0; i < road; ++i)
    add({-4.0 * height + 8.0 * height * u(rng), height, 2.0 * height + 10.0 * height * u(rng)});
  for (int i = 0; i < facade; ++i) {
    const double side = i % 2 ? 1.0 : -1.0;
    add({side * 5.0 * height, height - 6.0 * height * u(rng), 2.0 * height + 20.0 * height * u(rng)});
  }
  for (int i = 0; i < sidewalk; ++i)
    add({3.0 * height + 2.0 * height * u(rng), 0.85 * height, 2.0 * height + 10.0 * height * u(rng)});
  return pts;
}

}  // namespace

TEST(GroundPlane, FindsTheRoadAmongFacadesAndASidewalk) {
  const auto pts = street(1.65, 0.0, 400, 600, 150, 0.002);
  const auto g = fitGroundPlane(pts, GroundPlaneConfig{});
  ASSERT_TRUE(g.valid);
  EXPECT_NEAR(g.height, 1.65, 0.01 * 1.65);
  EXPECT_GT(g.normal_c.y(), std::cos(2.0 * M_PI / 180.0));
  EXPECT_GE(g.inliers, 380);
  EXPECT_LT(g.inliers, 400 + 20);  // not the sidewalk's points
}

TEST(GroundPlane, HeightDoesNotDependOnTheUnitsOrAPitchedCamera) {
  for (const double h : {0.05, 1.0, 40.0}) {
    const auto g = fitGroundPlane(street(h, 8.0, 300, 300, 0, 0.002), GroundPlaneConfig{});
    ASSERT_TRUE(g.valid) << h;
    EXPECT_NEAR(g.height / h, 1.0, 0.01) << h;
    EXPECT_NEAR(std::acos(g.normal_c.y()) * 180.0 / M_PI, 8.0, 0.5) << h;
  }
}

TEST(GroundPlane, NoPlaneWithoutEnoughRoad) {
  GroundPlaneConfig cfg;
  EXPECT_FALSE(fitGroundPlane(street(1.0, 0.0, 60, 600, 0), cfg).valid);  // too few road points
  EXPECT_FALSE(fitGroundPlane(street(1.0, 0.0, 0, 900, 0), cfg).valid);   // facades only
  EXPECT_FALSE(fitGroundPlane(street(1.0, 30.0, 400, 0, 0), cfg).valid);  // tilted beyond max_tilt_deg
  EXPECT_FALSE(fitGroundPlane({}, cfg).valid);
  // Clutter below the horizon (cars, bushes) outnumbering the road: the plane
  // holds less than min_inlier_fraction of the candidates.
  auto cluttered = street(1.0, 0.0, 150, 0, 0);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int i = 0; i < 600; ++i) cluttered.push_back({8.0 * u(rng) - 4.0, 0.3 + 0.6 * u(rng), 2.0 + 8.0 * u(rng)});
  EXPECT_FALSE(fitGroundPlane(cluttered, cfg).valid);
  cfg.min_inlier_fraction = 0.1;
  EXPECT_TRUE(fitGroundPlane(cluttered, cfg).valid);
}

TEST(GroundPlane, NonFinitePointsAreIgnored) {
  auto pts = street(1.0, 0.0, 300, 0, 0);
  pts.push_back(Eigen::Vector3d(std::nan(""), 1.0, 3.0));
  pts.push_back(Eigen::Vector3d(0.0, INFINITY, 3.0));
  const auto g = fitGroundPlane(pts, GroundPlaneConfig{});
  ASSERT_TRUE(g.valid);
  EXPECT_NEAR(g.height, 1.0, 0.01);
}

TEST(GroundPlane, BadConfigIsRefusedByName) {
  GroundPlaneConfig cfg;
  cfg.max_tilt_deg = 95.0;
  EXPECT_THROW(cfg.validate(), std::invalid_argument);
  cfg = GroundPlaneConfig{};
  cfg.min_inliers = 2;
  try {
    cfg.validate();
    FAIL() << "min_inliers 2 accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("min_inliers"), std::string::npos);
  }
}

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
