// Delaunay triangulation and FrameMesher filters.
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <random>

#include "vitamin_e/camera/camera.h"
#include "vitamin_e/meshing/delaunay.h"
#include "vitamin_e/meshing/frame_mesher.h"

using namespace vitamin_e::meshing;
using Eigen::Vector2d;

namespace {

// Number of points on the convex hull boundary (collinear boundary points included).
int hullBoundaryCount(std::vector<Vector2d> p) {
  std::sort(p.begin(), p.end(),
            [](const Vector2d& a, const Vector2d& b) { return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y()); });
  std::vector<Vector2d> h;
  auto build = [&](const auto& begin, const auto& end) {
    const std::size_t base = h.size();
    for (auto it = begin; it != end; ++it) {
      while (h.size() >= base + 2 && orient2d(h[h.size() - 2], h.back(), *it) < 0.0) h.pop_back();
      h.push_back(*it);
    }
    h.pop_back();
  };
  build(p.begin(), p.end());
  build(p.rbegin(), p.rend());
  return static_cast<int>(h.size());
}

void expectDelaunay(const std::vector<Vector2d>& p, const std::vector<Eigen::Vector3i>& tris, double tol) {
  for (const auto& t : tris) {
    ASSERT_GT(orient2d(p[t[0]], p[t[1]], p[t[2]]), 0.0) << "triangle not counter-clockwise or degenerate";
    // Scale-aware tolerance on the in-circle determinant.
    for (std::size_t k = 0; k < p.size(); ++k) {
      if (static_cast<int>(k) == t[0] || static_cast<int>(k) == t[1] || static_cast<int>(k) == t[2]) continue;
      ASSERT_LE(inCircle(p[t[0]], p[t[1]], p[t[2]], p[k]), tol) << "point " << k << " inside a circumcircle";
    }
  }
}

// Every interior edge is shared by exactly two triangles with opposite directions.
void expectManifold(const std::vector<Eigen::Vector3i>& tris) {
  std::map<std::pair<int, int>, int> directed;
  for (const auto& t : tris)
    for (int k = 0; k < 3; ++k) ++directed[{t[k], t[(k + 1) % 3]}];
  for (const auto& [e, c] : directed) EXPECT_EQ(c, 1) << "edge " << e.first << "-" << e.second << " repeated";
}

}  // namespace

TEST(Delaunay, RandomPointsAreDelaunayWithEulerCount) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> U(0.0, 640.0);
  for (int n : {3, 10, 100, 1000}) {
    std::vector<Vector2d> p(n);
    for (auto& q : p) q = {U(rng), U(rng) * 0.75};
    const auto tris = delaunayTriangulate(p);
    const int h = hullBoundaryCount(p);
    EXPECT_EQ(static_cast<int>(tris.size()), 2 * n - 2 - h) << "n=" << n;
    expectDelaunay(p, tris, 1e-6);
    expectManifold(tris);
  }
}

TEST(FrameMesh, EdgesAreEveryTrianglesSidesSortedOnce) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> U(0.0, 640.0);
  std::vector<Vector2d> p(500);
  for (auto& q : p) q = {U(rng), U(rng) * 0.75};
  FrameMesh mesh;
  mesh.vertices.resize(p.size() + 1);  // the last vertex is in no triangle
  mesh.triangles = delaunayTriangulate(p);
  std::shuffle(mesh.triangles.begin(), mesh.triangles.end(), rng);
  std::vector<std::pair<int, int>> expected;
  for (const auto& t : mesh.triangles)
    for (int k = 0; k < 3; ++k) expected.emplace_back(std::min(t[k], t[(k + 1) % 3]), std::max(t[k], t[(k + 1) % 3]));
  std::sort(expected.begin(), expected.end());
  expected.erase(std::unique(expected.begin(), expected.end()), expected.end());
  const int h = hullBoundaryCount(p);
  // Euler: a triangulation of n points with h on the hull has 3n - 3 - h edges.
  EXPECT_EQ(static_cast<int>(expected.size()), 3 * 500 - 3 - h);
  EXPECT_EQ(mesh.edges(), expected);
  EXPECT_TRUE(FrameMesh{}.edges().empty());
}

TEST(Delaunay, RegularGridCocircularPoints) {
  std::vector<Vector2d> p;
  const int W = 20, H = 13;
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) p.emplace_back(10.0 * x, 10.0 * y);
  const auto tris = delaunayTriangulate(p);
  EXPECT_EQ(static_cast<int>(tris.size()), 2 * (W - 1) * (H - 1));
  expectDelaunay(p, tris, 1e-3);
  expectManifold(tris);
}

TEST(Delaunay, DegenerateInputs) {
  EXPECT_TRUE(delaunayTriangulate({}).empty());
  EXPECT_TRUE(delaunayTriangulate({{0, 0}, {1, 1}}).empty());
  EXPECT_TRUE(delaunayTriangulate({{0, 0}, {1, 1}, {2, 2}, {3, 3}}).empty());
  // Duplicates are skipped: a square with a doubled corner still gives 2 triangles.
  const auto tris = delaunayTriangulate({{0, 0}, {1, 0}, {1, 1}, {0, 1}, {1, 1}});
  EXPECT_EQ(tris.size(), 2u);
}

// Timing is measured by bench_meshing_delaunay (./scripts/bench_delaunay.sh), not here.
TEST(Delaunay, TenThousandPoints) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  std::vector<Vector2d> p(10000);
  for (auto& q : p) q = {752.0 * U(rng), 480.0 * U(rng)};
  const auto tris = delaunayTriangulate(p);
  EXPECT_EQ(static_cast<int>(tris.size()), 2 * 10000 - 2 - hullBoundaryCount(p));
  expectManifold(tris);
}

namespace {
PinholeImage testImage() { return {{400.0, 400.0, 320.0, 240.0}, 640, 480}; }
}  // namespace

TEST(FrameMesher, DropsStepLongAndObliqueTriangles) {
  const PinholeImage image = testImage();
  std::vector<std::uint64_t> ids;
  std::vector<Vector2d> uv;
  std::vector<double> depth;
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> J(-3.0, 3.0);
  std::uint64_t id = 0;
  for (int y = 20; y < 460; y += 20)
    for (int x = 20; x < 620; x += 20) {
      ids.push_back(id++);
      uv.emplace_back(x + J(rng), y + J(rng));
      depth.push_back(x < 320 ? 2.0 : 4.0);  // step between two fronto-parallel planes
    }
  FrameMesherConfig cfg;
  cfg.max_edge_px = 40.0;
  FrameMesher mesher(cfg);
  const FrameMesh mesh = mesher.build(ids, uv, depth, image);
  ASSERT_GT(mesh.triangles.size(), 500u);
  for (const auto& t : mesh.triangles) {
    const double lo =
        std::min({mesh.vertices[t[0]].inv_depth, mesh.vertices[t[1]].inv_depth, mesh.vertices[t[2]].inv_depth});
    const double hi =
        std::max({mesh.vertices[t[0]].inv_depth, mesh.vertices[t[1]].inv_depth, mesh.vertices[t[2]].inv_depth});
    EXPECT_DOUBLE_EQ(lo, hi) << "triangle spans the step";
  }
  // Without the jump filter the step is bridged by triangles that are oblique to the rays.
  cfg.max_inv_depth_jump = 10.0;
  cfg.max_normal_angle_deg = 90.0;
  const FrameMesh bridged = FrameMesher(cfg).build(ids, uv, depth, image);
  EXPECT_GT(bridged.triangles.size(), mesh.triangles.size());
  cfg.max_normal_angle_deg = 75.0;
  const FrameMesh oblique = FrameMesher(cfg).build(ids, uv, depth, image);
  EXPECT_EQ(oblique.triangles.size(), mesh.triangles.size());

  // A far outlier point creates long edges to it: they are removed.
  ids.push_back(id++);
  uv.emplace_back(630.0, 470.0);
  depth.push_back(2.0);
  const FrameMesh with_far = mesher.build(ids, uv, depth, image);
  for (const auto& t : with_far.triangles)
    for (int k = 0; k < 3; ++k)
      EXPECT_LE((with_far.vertices[t[k]].uv - with_far.vertices[t[(k + 1) % 3]].uv).norm(), 40.0);
  // Invalid input.
  EXPECT_THROW(mesher.build({1}, {}, {}, image), std::invalid_argument);
  cfg.max_edge_px = -1.0;
  EXPECT_THROW(FrameMesher{cfg}, std::invalid_argument);
}

TEST(PinholeImage, FromCameraAndValidation) {
  const vitamin_e::camera::Camera cam(752, 480, 458.6, 457.3, 367.2, 248.4);
  const PinholeImage image = pinholeImageOf(cam);
  EXPECT_EQ(image.width, 752);
  EXPECT_EQ(image.height, 480);
  EXPECT_DOUBLE_EQ(image.K.cy, 248.4);
  const Eigen::Vector3d p(0.3, -0.2, 2.0);
  EXPECT_TRUE((image.K.ray(image.K.projectPoint(p)) * 2.0).isApprox(p, 1e-12));
  EXPECT_TRUE(image.inImage(Eigen::Vector2d(751.0, 0.0)));
  EXPECT_FALSE(image.inImage(Eigen::Vector2d(751.5, 0.0)));
  PinholeImage bad = image;
  bad.K.fx = 0.0;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
  bad = image;
  bad.height = 0;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
