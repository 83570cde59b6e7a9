// Marching cubes case table: every one of the 256 cases, random fields and a
// sphere give closed, outward-oriented surfaces.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>
#include <set>

#include <Eigen/Geometry>

#include "mesh_checks.h"
#include "vitamin_e/fusion/marching_cubes.h"

using namespace vitamin_e;
using fusion::TriangleMesh;
using test::openEdges;

namespace {

// Signed enclosed volume (divergence theorem): > 0 when the normals point out.
double signedVolume(const TriangleMesh& mesh) {
  double v = 0.0;
  for (const auto& f : mesh.faces) {
    const Eigen::Vector3d a = mesh.vertices[f[0]].cast<double>(), b = mesh.vertices[f[1]].cast<double>(),
                          c = mesh.vertices[f[2]].cast<double>();
    v += a.dot(b.cross(c)) / 6.0;
  }
  return v;
}

std::size_t edgeCount(const TriangleMesh& mesh) {
  std::set<std::pair<int, int>> e;
  for (const auto& f : mesh.faces)
    for (int k = 0; k < 3; ++k) e.insert({std::min(f[k], f[(k + 1) % 3]), std::max(f[k], f[(k + 1) % 3])});
  return e.size();
}

}  // namespace

TEST(MarchingCubes, EdgesJoinTheirCorners) {
  for (int e = 0; e < 12; ++e) {
    const int lo = fusion::mc::edgeLowerCorner(e), axis = fusion::mc::edgeAxis(e);
    EXPECT_EQ(lo & (1 << axis), 0) << "edge " << e;
  }
}

TEST(MarchingCubes, EveryCaseInsidePositiveShellIsClosedAndOutward) {
  // 4x4x4 grid: the centre cube's corners carry the case, the shell is outside.
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> mag(0.1f, 1.0f);
  for (int mask = 0; mask < 256; ++mask) {
    std::vector<float> v(64, 1.0f);
    for (int c = 0; c < 8; ++c) {
      const int x = 1 + (c & 1), y = 1 + ((c >> 1) & 1), z = 1 + ((c >> 2) & 1);
      v[x + 4 * (y + 4 * z)] = ((mask >> c) & 1) ? -mag(rng) : mag(rng);
    }
    const TriangleMesh mesh = fusion::mc::marchingCubesGrid(v, 4, 4, 4, 1.0f);
    if (mask == 0) {
      EXPECT_TRUE(mesh.faces.empty());
      continue;
    }
    EXPECT_FALSE(mesh.faces.empty()) << "case " << mask;
    EXPECT_EQ(openEdges(mesh), 0) << "case " << mask;
    EXPECT_GT(signedVolume(mesh), 0.0) << "case " << mask;
  }
}

TEST(MarchingCubes, RandomFieldsGiveClosedSurfaces) {
  for (unsigned seed = 0; seed < 5; ++seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> U(-1.0f, 1.0f);
    const int n = 12;
    std::vector<float> v(static_cast<std::size_t>(n) * n * n);
    for (int z = 0; z < n; ++z)
      for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
          const bool border = x == 0 || y == 0 || z == 0 || x == n - 1 || y == n - 1 || z == n - 1;
          float f = U(rng);
          if (f == 0.0f) f = 0.5f;
          v[x + n * (y + n * z)] = border ? 1.0f : f;
        }
    const TriangleMesh mesh = fusion::mc::marchingCubesGrid(v, n, n, n, 0.1f);
    ASSERT_GT(mesh.faces.size(), 100u);
    EXPECT_EQ(openEdges(mesh), 0) << "seed " << seed;
    EXPECT_GT(signedVolume(mesh), 0.0) << "seed " << seed;
  }
}

TEST(MarchingCubes, SphereIsWithinOneVoxelClosedAndOfGenusZero) {
  const int n = 24;
  const float h = 0.1f;
  const Eigen::Vector3d c(1.13, 1.21, 1.07);
  const double r = 0.8;
  std::vector<float> v(static_cast<std::size_t>(n) * n * n);
  for (int z = 0; z < n; ++z)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x)
        v[x + n * (y + n * z)] = static_cast<float>((Eigen::Vector3d(x, y, z) * h - c).norm() - r);
  const TriangleMesh mesh = fusion::mc::marchingCubesGrid(v, n, n, n, h);
  ASSERT_GT(mesh.faces.size(), 500u);
  double worst = 0.0;
  for (const auto& p : mesh.vertices) worst = std::max(worst, std::abs((p.cast<double>() - c).norm() - r));
  EXPECT_LT(worst, h);
  EXPECT_EQ(openEdges(mesh), 0);
  // Euler characteristic of a sphere: V - E + F = 2.
  EXPECT_EQ(static_cast<long>(mesh.vertices.size()) - static_cast<long>(edgeCount(mesh)) +
                static_cast<long>(mesh.faces.size()),
            2);
  EXPECT_NEAR(signedVolume(mesh), 4.0 / 3.0 * M_PI * r * r * r, 0.03 * 4.0 / 3.0 * M_PI * r * r * r);
}

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
