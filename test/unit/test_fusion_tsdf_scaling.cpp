// The TSDF after a rescale of the map (a ground-scale correction): the volume
// follows the map (its surface scaled about the centre, exactly), frames fused
// after it land on the same surface, the scaling survives a save and a load,
// and DenseMapper applies a DenseFrame's map scaling in order with its frames,
// also on its own thread and when frames are dropped.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>

#include "mesh_checks.h"
#include "sphere_views.h"
#include "vitamin_e/fusion/dense_mapper.h"
#include "vitamin_e/fusion/tsdf_volume.h"

using namespace vitamin_e;
using Eigen::Isometry3d;
using Eigen::Vector3d;
using test::lookAt;
using test::sphereDepth;

namespace {

fusion::TsdfConfig sphereConfig() {
  fusion::TsdfConfig c;
  c.voxel_size = 0.03;
  c.truncation = 0.09;
  return c;
}

// The map scaled by f about c: a pose's centre moves, its rotation stays.
Isometry3d scaledPose(const Isometry3d& T, const Vector3d& c, double f) {
  Isometry3d S = T;
  S.translation() = c + f * (T.translation() - c);
  return S;
}

// Largest distance of a mesh vertex from the sphere (centre, radius).
double worstSphereError(const fusion::TriangleMesh& mesh, const Vector3d& centre, double r) {
  double worst = 0.0;
  for (const auto& v : mesh.vertices) worst = std::max(worst, std::abs((v.cast<double>() - centre).norm() - r));
  return worst;
}

const Vector3d kSphere(0.3, -0.2, 0.5);
constexpr double kRadius = 0.4;
const Vector3d kCentre(1.6, 0.3, 0.2);  // the camera centre the map is scaled about
constexpr double kFactor = 1.1;

}  // namespace

// Half the views fused at one scale, the map then scaled by 10 % about a camera
// centre, the other half fused at the new scale: with the rescale the mesh is
// the scaled sphere within a voxel, without it the two halves disagree by ~5 voxels.
TEST(TsdfScaling, FramesAfterARescaleLandOnTheRescaledSurface) {
  const meshing::PinholeImage image = test::sphereTestImage();
  const std::vector<Isometry3d> views = test::viewsAround(kSphere, 1.5);
  const Vector3d sphere_after = kCentre + kFactor * (kSphere - kCentre);
  fusion::TsdfVolume rescaled(sphereConfig()), mixed(sphereConfig());
  for (std::size_t k = 0; k < views.size(); ++k) {
    if (k == views.size() / 2) rescaled.rescale(kCentre, kFactor);
    const bool after = k >= views.size() / 2;
    const Isometry3d T = after ? scaledPose(views[k], kCentre, kFactor) : views[k];
    const std::vector<float> depth =
        after ? sphereDepth(sphere_after, kFactor * kRadius, T, image) : sphereDepth(kSphere, kRadius, T, image);
    rescaled.integrateDepth(depth, T, image);
    mixed.integrateDepth(depth, T, image);
  }
  const fusion::TriangleMesh mesh = rescaled.extractMesh();
  ASSERT_GT(mesh.faces.size(), 1000u);
  const double worst = worstSphereError(mesh, sphere_after, kFactor * kRadius);
  const double worst_mixed = worstSphereError(mixed.extractMesh(), sphere_after, kFactor * kRadius);
  std::printf("[rescaled sphere] worst vertex error %.4f with the rescale, %.4f without (voxel %.3f)\n", worst,
              worst_mixed, kFactor * sphereConfig().voxel_size);
  EXPECT_LT(worst, 0.012);  // measured 0.008: a quarter of a voxel
  EXPECT_EQ(test::openEdges(mesh), 0);
  // The same frames without the rescale: the first half's surface where the map was (measured 0.18).
  EXPECT_GT(worst_mixed, 0.12);
}

// A rescale moves the surface exactly (no voxel is resampled) and distances scale with it.
TEST(TsdfScaling, RescaleScalesTheMeshAndTheDistancesExactly) {
  const meshing::PinholeImage image = test::sphereTestImage();
  fusion::TsdfVolume volume(sphereConfig());
  for (const auto& T : test::viewsAround(kSphere, 1.5))
    volume.integrateDepth(sphereDepth(kSphere, kRadius, T, image), T, image);
  const fusion::TriangleMesh before = volume.extractMesh();
  std::vector<double> sdf_before;
  // Inside voxels, not on their faces (where a rounding picks either side).
  const std::vector<Vector3d> probes = {kSphere + Vector3d(0.383, 0.004, 0.011),
                                        kSphere + Vector3d(0.007, -0.417, 0.013),
                                        kSphere + Vector3d(0.204, 0.197, 0.251)};
  for (const Vector3d& p : probes) {
    double d = 0.0;
    ASSERT_TRUE(volume.sdfAt(p, &d));
    sdf_before.push_back(d);
  }
  volume.rescale(kCentre, kFactor);
  volume.rescale(kCentre + Vector3d(0.1, 0.0, 0.0), 0.95);  // two corrections compose
  const fusion::MapScaling s = fusion::MapScaling::about(kCentre + Vector3d(0.1, 0.0, 0.0), 0.95)
                                   .after(fusion::MapScaling::about(kCentre, kFactor));
  EXPECT_NEAR(volume.scaling().scale, kFactor * 0.95, 1e-12);
  EXPECT_LT((volume.scaling().offset - s.offset).norm(), 1e-12);
  const fusion::TriangleMesh after = volume.extractMesh();
  ASSERT_EQ(after.faces.size(), before.faces.size());
  ASSERT_EQ(after.vertices.size(), before.vertices.size());
  for (std::size_t i = 0; i < before.vertices.size(); ++i) {
    EXPECT_LT((after.vertices[i].cast<double>() - s.apply(before.vertices[i].cast<double>())).norm(), 1e-5);
    EXPECT_LT((after.normals[i] - before.normals[i]).norm(), 1e-5);
  }
  for (std::size_t k = 0; k < probes.size(); ++k) {
    double d = 0.0;
    ASSERT_TRUE(volume.sdfAt(s.apply(probes[k]), &d));
    EXPECT_NEAR(d, s.scale * sdf_before[k], 1e-6) << "probe " << k;
  }
  // forEachVoxel gives the voxel centres where they are now.
  std::size_t n = 0;
  volume.forEachVoxel([&](const Vector3d& p, const fusion::Voxel& v) {
    if (n++ % 97 != 0) return;
    EXPECT_EQ(volume.voxelAt(p), &v);
  });
  EXPECT_GT(n, 1000u);
  EXPECT_THROW(volume.rescale(kCentre, 0.0), std::invalid_argument);
  volume.clear();
  EXPECT_TRUE(volume.scaling().isIdentity());
}

TEST(TsdfScaling, SavedAndLoadedWithItsScaling) {
  const meshing::PinholeImage image = test::sphereTestImage();
  fusion::TsdfVolume volume(sphereConfig());
  const auto views = test::viewsAround(kSphere, 1.5);
  for (std::size_t k = 0; k < 8; ++k)
    volume.integrateDepth(sphereDepth(kSphere, kRadius, views[k], image), views[k], image);
  volume.rescale(kCentre, kFactor);
  const std::string path = testing::TempDir() + "/ve_tsdf_scaling_" + std::to_string(::getpid()) + ".vetsdf";
  std::string error;
  ASSERT_TRUE(volume.save(path, &error)) << error;
  std::string first_line;
  std::getline(std::ifstream(path), first_line);
  EXPECT_EQ(first_line.rfind("vitamin_e tsdf v2, ", 0), 0u) << first_line;
  fusion::TsdfVolume loaded(sphereConfig());
  loaded.load(path);
  EXPECT_EQ(loaded.scaling(), volume.scaling());
  const fusion::TriangleMesh a = volume.extractMesh(), b = loaded.extractMesh();
  ASSERT_EQ(a.vertices.size(), b.vertices.size());
  ASSERT_GT(a.vertices.size(), 100u);
  // Both assembled from the blocks in the same (sorted) order only after a load: compare as sets.
  std::vector<std::array<float, 3>> va, vb;
  for (const auto& v : a.vertices) va.push_back({v.x(), v.y(), v.z()});
  for (const auto& v : b.vertices) vb.push_back({v.x(), v.y(), v.z()});
  std::sort(va.begin(), va.end());
  std::sort(vb.begin(), vb.end());
  EXPECT_EQ(va, vb);
  std::remove(path.c_str());
}

namespace {

meshing::PinholeImage planeImage() { return {{400.0, 400.0, 320.0, 240.0}, 640, 480}; }

// Points of the plane z = plane_z (world) seen by a camera at T_w_c looking along +z.
fusion::DenseFrame planeFrame(const Isometry3d& T_w_c, double plane_z, std::mt19937* rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const meshing::PinholeImage im = planeImage();
  fusion::DenseFrame f;
  f.T_w_c = T_w_c;
  const Isometry3d T_c_w = T_w_c.inverse();
  for (std::uint64_t id = 0; id < 2000; ++id) {
    const Vector3d ray_w = T_w_c.linear() * im.K.ray({u(*rng) * (im.width - 1), u(*rng) * (im.height - 1)});
    const double s = (plane_z - T_w_c.translation().z()) / ray_w.z();
    f.ids.push_back(id);
    f.p_c.push_back(T_c_w * (T_w_c.translation() + s * ray_w));
  }
  return f;
}

// Frames of a plane at z = 3 from cameras moving along x; after frame `correct_at`
// the map is scaled by `factor` about that frame's camera centre (the frames then
// carry the scaling, their poses and points are in the new scale).
std::vector<fusion::DenseFrame> correctedPlaneFrames(int frames, int correct_at, double factor) {
  std::mt19937 rng(3);
  std::vector<fusion::DenseFrame> out;
  fusion::MapScaling map;
  for (int k = 0; k < frames; ++k) {
    Isometry3d T = Isometry3d::Identity();
    T.translation() = Vector3d(0.15 * k, 0.05 * k, 0.0);
    if (k == correct_at) map = fusion::MapScaling::about(map.apply(T.translation()), factor).after(map);
    Isometry3d T_now = T;
    T_now.translation() = map.apply(T.translation());
    // The plane in the map as it is now: its z scaled like every other point.
    const double plane_z = map.apply(Vector3d(0.0, 0.0, 3.0)).z();
    fusion::DenseFrame f = planeFrame(T_now, plane_z, &rng);
    f.frame_index = static_cast<std::uint64_t>(k);
    f.map_scaling = map;
    out.push_back(std::move(f));
  }
  return out;
}

fusion::DenseMapperConfig planeMapperConfig(bool asynchronous) {
  fusion::DenseMapperConfig cfg;
  cfg.integrator.tsdf.voxel_size = 0.05;
  cfg.integrator.tsdf.truncation = 0.15;
  cfg.integrator.asynchronous = asynchronous;
  cfg.integrator.block_when_full = true;
  return cfg;
}

double worstPlaneError(const fusion::TriangleMesh& mesh, double z) {
  double worst = 0.0;
  for (const auto& v : mesh.vertices) worst = std::max(worst, std::abs(v.z() - z));
  return worst;
}

}  // namespace

// DenseMapper takes the map's scaling with each frame: the volume is rescaled
// before the frame is fused, so the whole mesh is the plane where the map has it now.
TEST(DenseMapperScaling, AFrameWithANewMapScalingRescalesTheVolumeFirst) {
  const auto frames = correctedPlaneFrames(6, 3, 1.2);
  const double plane_now = frames.back().map_scaling.apply(Vector3d(0.0, 0.0, 3.0)).z();
  fusion::DenseMapper mapper(planeMapperConfig(false), planeImage());
  fusion::DenseMapper unscaled(planeMapperConfig(false), planeImage());
  for (const auto& f : frames) {
    EXPECT_TRUE(mapper.addFrame(f).integrated);
    fusion::DenseFrame without = f;
    without.map_scaling = fusion::MapScaling{};
    unscaled.addFrame(without);
  }
  EXPECT_EQ(mapper.scaling(), frames.back().map_scaling);
  const fusion::TriangleMesh mesh = mapper.extractMesh();
  ASSERT_GT(mesh.faces.size(), 100u);
  const double worst = worstPlaneError(mesh, plane_now),
               worst_unscaled = worstPlaneError(unscaled.extractMesh(), plane_now);
  std::printf("[rescaled plane] worst vertex error %.4f with the map's scaling, %.4f without\n", worst, worst_unscaled);
  EXPECT_LT(worst, 0.0005);         // measured 0.0003: noise-free points, a hundredth of a voxel
  EXPECT_GT(worst_unscaled, 0.55);  // the first frames' plane at z = 3, 0.6 from z = 3.6

  // The same through rescale() by hand: the same volume.
  fusion::DenseMapper by_hand(planeMapperConfig(false), planeImage());
  for (const auto& f : frames) {
    // Frame 3's camera centre is the fixed point of the correction.
    if (f.frame_index == 3) by_hand.rescale(f.T_w_c.translation(), 1.2);
    by_hand.addFrame(f.ids, f.p_c, f.T_w_c);
  }
  const fusion::TriangleMesh again = by_hand.extractMesh();
  ASSERT_EQ(again.vertices.size(), mesh.vertices.size());
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i)
    EXPECT_LT((again.vertices[i] - mesh.vertices[i]).norm(), 1e-5f);

  fusion::DenseFrame bad = frames.back();
  bad.map_scaling.scale = -1.0;
  EXPECT_THROW(mapper.addFrame(bad), std::invalid_argument);
  mapper.reset();
  EXPECT_TRUE(mapper.scaling().isIdentity());
}

// On the integrator's thread the scaling is applied in order with the frames:
// the same mesh as synchronously; with a queue that drops frames, the frames
// that are fused still all land on the rescaled plane (a scaling is never dropped).
TEST(DenseMapperScaling, TheScalingKeepsItsPlaceInTheQueue) {
  const auto frames = correctedPlaneFrames(8, 4, 0.8);
  const double plane_now = frames.back().map_scaling.apply(Vector3d(0.0, 0.0, 3.0)).z();
  fusion::DenseMapper sync(planeMapperConfig(false), planeImage()), async(planeMapperConfig(true), planeImage());
  fusion::DenseMapperConfig dropping_cfg = planeMapperConfig(true);
  dropping_cfg.integrator.block_when_full = false;
  dropping_cfg.integrator.queue_capacity = 1;
  fusion::DenseMapper dropping(dropping_cfg, planeImage());
  for (const auto& f : frames) {
    sync.addFrame(f);
    async.addFrame(f);
    dropping.addFrame(f);
  }
  const fusion::TriangleMesh a = sync.extractMesh(), b = async.extractMesh(), c = dropping.extractMesh();
  ASSERT_EQ(a.vertices.size(), b.vertices.size());
  for (std::size_t i = 0; i < a.vertices.size(); ++i) EXPECT_EQ(a.vertices[i], b.vertices[i]);
  ASSERT_GT(c.faces.size(), 100u);
  EXPECT_LT(worstPlaneError(c, plane_now), 0.0005);
  const fusion::TsdfIntegratorStats stats = dropping.integratorStats();
  EXPECT_EQ(stats.integrated + stats.dropped, frames.size());
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
