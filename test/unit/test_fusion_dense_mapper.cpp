// DenseMapper: frame points in, fused mesh out, on a known plane.
#include <gtest/gtest.h>

#include <random>
#include <stdexcept>
#include <string>

#include "vitamin_e/fusion/dense_mapper.h"

using namespace vitamin_e;

namespace {

fusion::DenseFrame denseFrame(const std::vector<std::uint64_t>& ids, const std::vector<Eigen::Vector3d>& p_c,
                              const Eigen::Isometry3d& T_w_c) {
  fusion::DenseFrame f;
  f.ids = ids;
  f.p_c = p_c;
  f.T_w_c = T_w_c;
  return f;
}
meshing::PinholeImage image() { return {{400.0, 400.0, 320.0, 240.0}, 640, 480}; }

// 5 cm voxels for the plane 3 m away.
fusion::DenseMapperConfig planeConfig() {
  fusion::DenseMapperConfig cfg;
  cfg.integrator.tsdf.voxel_size = 0.05;
  cfg.integrator.tsdf.truncation = 0.15;
  return cfg;
}

// Points on the plane z = 3 (world) seen by a camera at T_w_c looking along +z.
void planePoints(const Eigen::Isometry3d& T_w_c, std::mt19937* rng, std::vector<std::uint64_t>* ids,
                 std::vector<Eigen::Vector3d>* p_c) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, 0.003);
  const meshing::PinholeImage im = image();
  ids->clear();
  p_c->clear();
  const Eigen::Isometry3d T_c_w = T_w_c.inverse();
  for (std::uint64_t id = 0; id < 3000; ++id) {
    const Eigen::Vector3d ray_c = im.K.ray({u(*rng) * (im.width - 1), u(*rng) * (im.height - 1)});
    const Eigen::Vector3d ray_w = T_w_c.linear() * ray_c;
    const double s = (3.0 - T_w_c.translation().z()) / ray_w.z();
    const Eigen::Vector3d p_w = T_w_c.translation() + s * ray_w;
    ids->push_back(id);
    p_c->push_back(T_c_w * p_w + Eigen::Vector3d(0, 0, noise(*rng)));
  }
}
}  // namespace

TEST(DenseMapper, FusesNoisyPlaneFramesIntoAFlatMesh) {
  fusion::DenseMapper mapper(planeConfig(), image());
  std::mt19937 rng(5);
  std::vector<std::uint64_t> ids;
  std::vector<Eigen::Vector3d> p_c;
  for (int k = 0; k < 6; ++k) {
    Eigen::Isometry3d T_w_c = Eigen::Isometry3d::Identity();
    T_w_c.translation() = Eigen::Vector3d(0.1 * k, 0.05 * k, 0.0);
    planePoints(T_w_c, &rng, &ids, &p_c);
    const fusion::DenseFrameStats s = mapper.addFrame(ids, p_c, T_w_c);
    EXPECT_TRUE(s.integrated);
    EXPECT_GT(s.triangles, 1000u);
  }
  const fusion::TriangleMesh mesh = mapper.extractMesh();
  ASSERT_GT(mesh.faces.size(), 100u);
  double max_err = 0.0;
  for (const auto& v : mesh.vertices) max_err = std::max(max_err, std::abs(v.z() - 3.0));
  EXPECT_LT(max_err, 0.05) << "a vertex is more than one voxel off the plane";
  EXPECT_EQ(mapper.integratorStats().integrated, 6u);
  // Every fused frame is counted under the raster size it was fused at.
  std::size_t counted = 0;
  for (const auto& [downscale, frames] : mapper.integratorStats().raster_downscale_frames) {
    EXPECT_GE(downscale, 1);
    EXPECT_LE(downscale, 16);
    counted += frames;
  }
  EXPECT_EQ(counted, 6u);
}

TEST(DenseMapper, SkipsFramesWithoutEnoughPointsOrPose) {
  fusion::DenseMapper mapper(fusion::DenseMapperConfig{}, image());
  std::vector<std::uint64_t> ids = {1, 2};
  std::vector<Eigen::Vector3d> p_c = {{0, 0, 1}, {0.1, 0, 1}};
  EXPECT_FALSE(mapper.addFrame(ids, p_c, Eigen::Isometry3d::Identity()).integrated);
  Eigen::Isometry3d bad = Eigen::Isometry3d::Identity();
  bad.translation().x() = std::nan("");
  std::mt19937 rng(1);
  planePoints(Eigen::Isometry3d::Identity(), &rng, &ids, &p_c);
  EXPECT_FALSE(mapper.addFrame(ids, p_c, bad).integrated);
  ids.pop_back();
  EXPECT_THROW(mapper.addFrame(ids, p_c, Eigen::Isometry3d::Identity()), std::invalid_argument);
}

// The meshing thread does addFrame's work in order: the same frames give the
// same fused mesh, none is lost, and bad input is refused at the call.
TEST(DenseMapper, SubmittedFramesGiveTheSameMeshAsAddFrame) {
  fusion::DenseMapperConfig cfg = planeConfig();
  cfg.integrator.block_when_full = true;
  fusion::DenseMapper inline_mapper(cfg, image());
  fusion::DenseMapper threaded(cfg, image());
  std::mt19937 rng(7);
  std::vector<std::uint64_t> ids;
  std::vector<Eigen::Vector3d> p_c;
  const int frames = 8;
  for (int k = 0; k < frames; ++k) {
    Eigen::Isometry3d T_w_c = Eigen::Isometry3d::Identity();
    T_w_c.translation() = Eigen::Vector3d(0.08 * k, -0.03 * k, 0.0);
    planePoints(T_w_c, &rng, &ids, &p_c);
    inline_mapper.addFrame(ids, p_c, T_w_c);
    threaded.submitFrame(denseFrame(ids, p_c, T_w_c), 2);
  }
  const fusion::TriangleMesh a = inline_mapper.extractMesh();
  const fusion::TriangleMesh b = threaded.extractMesh();  // waits for the meshing thread
  ASSERT_GT(a.faces.size(), 100u);
  ASSERT_EQ(a.vertices.size(), b.vertices.size());
  ASSERT_EQ(a.faces.size(), b.faces.size());
  for (std::size_t i = 0; i < a.vertices.size(); ++i) EXPECT_EQ(a.vertices[i], b.vertices[i]) << i;
  const fusion::DenseWorkStats w = threaded.workStats();
  EXPECT_EQ(w.submitted, static_cast<std::size_t>(frames));
  EXPECT_EQ(w.meshed, static_cast<std::size_t>(frames));
  EXPECT_EQ(threaded.meshTimings().summary("mesh").count, static_cast<std::size_t>(frames));
  EXPECT_EQ(threaded.integratorStats().integrated, static_cast<std::size_t>(frames));
  EXPECT_EQ(threaded.integratorStats().dropped, 0u);
  ids.pop_back();
  EXPECT_THROW(threaded.submitFrame(denseFrame(ids, p_c, Eigen::Isometry3d::Identity())), std::invalid_argument);
}

// A live caller (the meshing nodelet) never waits for the meshing thread: beyond
// `max_waiting` frames the oldest waiting one is dropped. Every frame submitted is
// either meshed or counted as dropped, and the newest one is never dropped.
TEST(DenseMapper, ALiveCallerDropsTheOldestWaitingFramesAndCountsThem) {
  fusion::DenseMapper mapper(planeConfig(), image());
  std::mt19937 rng(11);
  std::vector<std::uint64_t> ids;
  std::vector<Eigen::Vector3d> p_c;
  planePoints(Eigen::Isometry3d::Identity(), &rng, &ids, &p_c);
  const int frames = 12;
  std::size_t dropped = 0;
  for (int k = 0; k < frames; ++k) {
    dropped += mapper.submitFrame(denseFrame(ids, p_c, Eigen::Isometry3d::Identity()), 1, WhenFull::kDropOldest);
  }
  mapper.flush();
  const fusion::DenseWorkStats w = mapper.workStats();
  EXPECT_EQ(w.submitted, static_cast<std::size_t>(frames));
  EXPECT_EQ(w.dropped, dropped);
  EXPECT_EQ(w.meshed + w.dropped, w.submitted);
  EXPECT_EQ(w.failed, 0u);
  EXPECT_GE(w.meshed, 1u);  // at least the newest
}

TEST(DenseMapper, RefusesANiceIncrementOutsideItsRangeNamingTheKey) {
  for (const int increment : {-1, 20}) {
    fusion::DenseMapperConfig cfg;
    cfg.nice_increment = increment;
    try {
      fusion::DenseMapper mapper(cfg, image());
      ADD_FAILURE() << increment << " was taken";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("dense.nice_increment"), std::string::npos) << e.what();
    }
  }
}

TEST(DenseMapper, ResetDropsWaitingFramesAndKeepsWorking) {
  fusion::DenseMapperConfig cfg = planeConfig();
  std::mt19937 rng(3);
  std::vector<std::uint64_t> ids;
  std::vector<Eigen::Vector3d> p_c;
  fusion::DenseMapper mapper(cfg, image());
  for (int k = 0; k < 3; ++k) {
    planePoints(Eigen::Isometry3d::Identity(), &rng, &ids, &p_c);
    mapper.submitFrame(denseFrame(ids, p_c, Eigen::Isometry3d::Identity()), 8);
  }
  mapper.reset();  // drops what waits, keeps working afterwards
  planePoints(Eigen::Isometry3d::Identity(), &rng, &ids, &p_c);
  mapper.submitFrame(denseFrame(ids, p_c, Eigen::Isometry3d::Identity()));
  mapper.flush();
  EXPECT_GE(mapper.workStats().meshed, 1u);
  for (int k = 0; k < 3; ++k) mapper.submitFrame(denseFrame(ids, p_c, Eigen::Isometry3d::Identity()), 8);
}  // destroyed with frames waiting: they are finished, then the thread joins

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
