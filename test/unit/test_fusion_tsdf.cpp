// TSDF integration and marching cubes on synthetic spheres and planes.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <random>

#include "mesh_checks.h"
#include "sphere_views.h"
#include "vitamin_e/fusion/tsdf_integrator.h"
#include "vitamin_e/fusion/tsdf_volume.h"
#include "vitamin_e/meshing/frame_mesher.h"

using namespace vitamin_e;
using Eigen::Isometry3d;
using Eigen::Vector3d;
using meshing::PinholeImage;

namespace {

using test::lookAt;
using test::sphereDepth;
using test::viewsAround;
PinholeImage smallImage() { return test::sphereTestImage(); }

// Frame mesh of the plane z = 0 (world) seen from T_w_c: jittered grid of points.
meshing::FrameMesh planeMesh(const Isometry3d& T_w_c, const PinholeImage& image, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> J(-2.0, 2.0);
  std::vector<std::uint64_t> ids;
  std::vector<Eigen::Vector2d> uv;
  std::vector<double> depth;
  const Vector3d o = T_w_c.translation();
  for (int v = 2; v < image.height - 2; v += 8)
    for (int u = 2; u < image.width - 2; u += 8) {
      const Eigen::Vector2d px(u + J(rng), v + J(rng));
      const Vector3d d_w = T_w_c.linear() * image.K.ray(px);  // z-unit ray in world
      if (d_w.z() >= -1e-6) continue;
      const double t = -o.z() / d_w.z();  // depth z (ray has z_c = 1)
      ids.push_back(ids.size());
      uv.push_back(px);
      depth.push_back(t);
    }
  meshing::FrameMesherConfig cfg;
  cfg.max_edge_px = 30.0;
  return meshing::FrameMesher(cfg).build(ids, uv, depth, image);
}

// Every undirected edge is shared by exactly two faces, in opposite directions.
void expectClosed(const fusion::TriangleMesh& mesh) {
  EXPECT_EQ(test::openEdges(mesh), 0) << "of " << 3 * mesh.faces.size() << " directed edges";
}

}  // namespace

TEST(Tsdf, SphereFromManyViewsIsAccurateAndClosed) {
  const PinholeImage image = smallImage();
  fusion::TsdfConfig cfg;
  cfg.voxel_size = 0.03;
  cfg.truncation = 0.09;
  fusion::TsdfVolume volume(cfg);
  const Vector3d c(0.31, -0.17, 0.52);
  const double r = 0.4;
  for (const auto& T : viewsAround(c, 1.5)) volume.integrateDepth(sphereDepth(c, r, T, image), T, image);
  const fusion::TriangleMesh mesh = volume.extractMesh();
  ASSERT_GT(mesh.faces.size(), 1000u);
  double worst = 0.0, normal_worst = 1.0, normal_mean = 0.0;
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
    const Vector3d p = mesh.vertices[i].cast<double>();
    worst = std::max(worst, std::abs((p - c).norm() - r));
    const double dot = mesh.normals[i].cast<double>().dot((p - c).normalized());
    normal_worst = std::min(normal_worst, dot);
    normal_mean += dot / static_cast<double>(mesh.vertices.size());
  }
  EXPECT_LT(worst, cfg.voxel_size);
  // Normals point out of the sphere (area-weighted face normals: a little bumpy).
  EXPECT_GT(normal_worst, 0.6);
  EXPECT_GT(normal_mean, 0.97);
  expectClosed(mesh);
}

TEST(Tsdf, PlaneFromFrameMeshesIsWithinOneVoxel) {
  const PinholeImage image = smallImage();
  fusion::TsdfConfig cfg;
  cfg.voxel_size = 0.05;
  cfg.truncation = 0.15;
  fusion::TsdfVolume volume(cfg);
  unsigned seed = 1;
  for (double x : {-0.5, 0.0, 0.5})
    for (double y : {-0.4, 0.4}) {
      const Isometry3d T = lookAt(Vector3d(x, y, 1.5), Vector3d(0.3 * x, 0.2, 0.0));
      volume.integrate(planeMesh(T, image, seed++), T, image);
    }
  const fusion::TriangleMesh mesh = volume.extractMesh();
  ASSERT_GT(mesh.faces.size(), 200u);
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
    EXPECT_LT(std::abs(mesh.vertices[i].z()), cfg.voxel_size);
    EXPECT_GT(mesh.normals[i].z(), 0.9f);  // facing the cameras
  }
}

// With a raster smaller than the image a voxel takes the measured depth from its triangle's plane
// at its own projection, so on a planar mesh its signed distance is the exact projective one
// whatever the raster's size (the raster's nearest pixel would be off by up to half a raster pixel
// times the slope: 16 mm at a quarter here). At full size it reads its nearest pixel (4 mm here).
TEST(Tsdf, VoxelsReadTheTrianglesPlaneAtTheirProjection) {
  const PinholeImage image = smallImage();
  const Isometry3d T = lookAt(Vector3d(0.3, -0.2, 1.1), Vector3d(0.0, 0.1, 0.0));  // slanted view of z = 0
  const meshing::FrameMesh mesh = planeMesh(T, image, 7);
  for (int s : {2, 4}) {
    fusion::TsdfConfig cfg;
    cfg.voxel_size = 0.02;
    cfg.truncation = 0.06;
    cfg.raster_downscale = s;
    fusion::TsdfVolume volume(cfg);
    EXPECT_EQ(volume.integrate(mesh, T, image).raster_downscale, s);
    const Isometry3d T_c_w = T.inverse();
    std::size_t checked = 0;
    double worst = 0.0;
    volume.forEachVoxel([&](const Vector3d& p_w, const fusion::Voxel& v) {
      // Along the ray from the camera through the voxel: the plane z = 0 at distance t * |ray|.
      const Vector3d ray_w = p_w - T.translation();
      const double t = -T.translation().z() / ray_w.z();  // the plane at camera + t * ray_w
      const double expected = (t - 1.0) * ray_w.norm();
      if (!(t > 0.0) || std::abs(expected) >= 0.9 * cfg.truncation) return;
      const Vector3d p_c = T_c_w * p_w;
      const Eigen::Vector2d uv = image.K.projectPoint(p_c);
      if (uv.x() < 20 || uv.y() < 20 || uv.x() > image.width - 20 || uv.y() > image.height - 20) return;  // mesh inside
      worst = std::max(worst, std::abs(v.sdf - expected));
      ++checked;
    });
    EXPECT_GT(checked, 2000u) << "raster_downscale " << s;
    EXPECT_LT(worst, 1e-5) << "raster_downscale " << s;
  }
}

// raster_downscale 0: half the voxel's size in pixels at the mesh's far depth (here a wall
// facing the camera at one depth: 200 px focal length x 0.05 / z), between 1 and 8.
TEST(Tsdf, AutomaticRasterFollowsTheVoxelsSizeInPixels) {
  const PinholeImage image = smallImage();
  for (const auto& [depth, expected] : std::vector<std::pair<double, int>>{{0.5, 8}, {1.0, 5}, {2.0, 2}, {6.0, 1}}) {
    const Isometry3d T = lookAt(Vector3d(0.0, 0.0, depth), Vector3d(0.0, 0.0, 0.0));
    fusion::TsdfConfig cfg;
    cfg.voxel_size = 0.05;
    cfg.truncation = 0.15;
    fusion::TsdfVolume volume(cfg);
    const fusion::IntegrationStats stats = volume.integrate(planeMesh(T, image, 3), T, image);
    EXPECT_EQ(stats.raster_downscale, expected) << "depth " << depth;
    EXPECT_GT(stats.voxels_updated, 1000u) << "depth " << depth;
  }
  // After the map was scaled by 2 the same voxel is twice as large in map units (and in pixels).
  const Isometry3d T = lookAt(Vector3d(0.0, 0.0, 2.0), Vector3d(0.0, 0.0, 0.0));
  fusion::TsdfConfig cfg;
  cfg.voxel_size = 0.05;
  cfg.truncation = 0.15;
  fusion::TsdfVolume volume(cfg);
  volume.rescale(Vector3d::Zero(), 2.0);
  EXPECT_EQ(volume.integrate(planeMesh(T, image, 3), T, image).raster_downscale, 5);
}

TEST(Tsdf, SameFrameTwiceOnlyChangesWeights) {
  const PinholeImage image = smallImage();
  const Isometry3d T = lookAt(Vector3d(0.2, 0.1, 1.2), Vector3d(0.0, 0.0, 0.0));
  const meshing::FrameMesh mesh = planeMesh(T, image, 5);
  fusion::TsdfVolume once, twice;
  once.integrate(mesh, T, image);
  twice.integrate(mesh, T, image);
  twice.integrate(mesh, T, image);
  ASSERT_EQ(once.numBlocks(), twice.numBlocks());
  std::size_t n = 0;
  once.forEachVoxel([&](const Vector3d& p, const fusion::Voxel& v) {
    const fusion::Voxel* w = twice.voxelAt(p);
    ASSERT_NE(w, nullptr);
    EXPECT_NEAR(w->sdf, v.sdf, 1e-6);
    EXPECT_FLOAT_EQ(w->weight, 2.0f * v.weight);
    ++n;
  });
  EXPECT_GT(n, 1000u);
  const auto m1 = once.extractMesh(), m2 = twice.extractMesh();
  EXPECT_EQ(m1.faces.size(), m2.faces.size());
}

TEST(Tsdf, IncrementalExtractionMatchesFullExtraction) {
  const PinholeImage image = smallImage();
  fusion::TsdfConfig cfg;
  cfg.voxel_size = 0.04;
  cfg.truncation = 0.12;
  const Vector3d c(0.0, 0.0, 0.0);
  const auto views = viewsAround(c, 1.5);
  fusion::TsdfVolume incremental(cfg), full(cfg);
  for (std::size_t k = 0; k < views.size(); ++k) {
    const auto depth = sphereDepth(c, 0.35, views[k], image);
    incremental.integrateDepth(depth, views[k], image);
    full.integrateDepth(depth, views[k], image);
    if (k % 5 == 0) incremental.extractMesh();
  }
  // One more partial view: only part of the blocks are re-meshed.
  const Isometry3d last = lookAt(Vector3d(1.5, 0.0, 0.2), c);
  incremental.extractMesh();
  incremental.integrateDepth(sphereDepth(c, 0.35, last, image), last, image);
  full.integrateDepth(sphereDepth(c, 0.35, last, image), last, image);
  const auto a = incremental.extractMesh();
  EXPECT_LT(incremental.lastRemeshedBlocks(), incremental.numBlocks());
  const auto b = full.extractMesh();
  ASSERT_EQ(a.faces.size(), b.faces.size());
  ASSERT_EQ(a.vertices.size(), b.vertices.size());
  auto key = [](const Eigen::Vector3f& p) {
    return std::make_tuple(std::lround(p.x() * 1e5), std::lround(p.y() * 1e5), std::lround(p.z() * 1e5));
  };
  std::map<std::tuple<long, long, long>, int> count;
  for (const auto& p : a.vertices) ++count[key(p)];
  for (const auto& p : b.vertices) --count[key(p)];
  for (const auto& [k, n] : count) EXPECT_EQ(n, 0);
  expectClosed(a);
}

TEST(Tsdf, AsyncIntegratorMatchesSynchronousAndWritesPly) {
  const PinholeImage image = smallImage();
  fusion::TsdfIntegratorConfig sync_cfg, async_cfg;
  sync_cfg.asynchronous = false;
  async_cfg.asynchronous = true;
  async_cfg.block_when_full = true;
  async_cfg.queue_capacity = 2;
  fusion::TsdfIntegrator sync(sync_cfg), async(async_cfg);
  for (int k = 0; k < 5; ++k) {
    const Isometry3d T = lookAt(Vector3d(0.3 * k - 0.6, 0.2, 1.3), Vector3d(0.0, 0.0, 0.0));
    const auto mesh = planeMesh(T, image, 20 + k);
    sync.submit(mesh, T, image);
    async.submit(mesh, T, image);
  }
  async.flush();
  EXPECT_EQ(async.stats().integrated, 5u);
  EXPECT_EQ(async.stats().dropped, 0u);
  const auto a = sync.extractMesh(), b = async.extractMesh();
  EXPECT_EQ(a.faces.size(), b.faces.size());
  EXPECT_GT(a.faces.size(), 100u);

  const std::string path = testing::TempDir() + "/vitamin_e_tsdf_test.ply";
  std::string error;
  ASSERT_TRUE(fusion::saveMeshPly(a, path, &error, false)) << error;
  std::ifstream in(path);
  std::string line, header;
  while (std::getline(in, line) && line != "end_header") header += line + "\n";
  EXPECT_NE(header.find("element vertex " + std::to_string(a.vertices.size())), std::string::npos);
  EXPECT_NE(header.find("element face " + std::to_string(a.faces.size())), std::string::npos);
  EXPECT_NE(header.find("property float nx"), std::string::npos);
  std::remove(path.c_str());
  EXPECT_FALSE(fusion::saveMeshPly(a, "/nonexistent_dir/x.ply", &error));
  EXPECT_FALSE(error.empty());
}

TEST(Tsdf, ConfigValidation) {
  fusion::TsdfConfig cfg;
  cfg.truncation = 0.01;  // < voxel size
  EXPECT_THROW(fusion::TsdfVolume{cfg}, std::invalid_argument);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
