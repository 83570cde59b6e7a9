// TsdfVolume::takeChangedBlocks, the mesh stream's source: a consumer that keeps
// the blocks it was given (replacing a block by its new surface, dropping one that
// lost it, starting over on replace_all) holds exactly extractMesh()'s triangles
// after every update, through new views, a rescale, a surface carved away, a
// clear and a load; and an update carries only the blocks near what changed.
#include <gtest/gtest.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <map>
#include <tuple>

#include "sphere_views.h"
#include "vitamin_e/fusion/tsdf_volume.h"

using namespace vitamin_e;
using Eigen::Isometry3d;
using Eigen::Vector3d;
using test::sphereDepth;

namespace {

using Triangle = std::array<float, 9>;
using BlockKey = std::tuple<int, int, int>;

// What a mesh stream's subscriber holds: the blocks' triangle soups.
struct BlockCopy {
  std::map<BlockKey, std::vector<Eigen::Vector3f>> blocks;
  std::size_t updates = 0;
  void apply(const fusion::MeshBlockUpdate& u) {
    ++updates;
    if (u.replace_all) blocks.clear();
    for (const auto& b : u.blocks) {
      const BlockKey key{b.index.x(), b.index.y(), b.index.z()};
      if (b.vertices.empty()) {
        EXPECT_EQ(blocks.erase(key), 1u) << "a block reported empty that was never given with a surface";
      } else {
        blocks[key] = b.vertices;
      }
    }
  }
  std::vector<Triangle> triangles() const {
    std::vector<Triangle> out;
    for (const auto& [key, v] : blocks) {
      EXPECT_EQ(v.size() % 3, 0u);
      for (std::size_t i = 0; i + 2 < v.size(); i += 3)
        out.push_back({v[i].x(), v[i].y(), v[i].z(), v[i + 1].x(), v[i + 1].y(), v[i + 1].z(), v[i + 2].x(),
                       v[i + 2].y(), v[i + 2].z()});
    }
    std::sort(out.begin(), out.end());
    return out;
  }
};

std::vector<Triangle> meshTriangles(const fusion::TriangleMesh& m) {
  std::vector<Triangle> out;
  for (const auto& f : m.faces) {
    const auto &a = m.vertices[f[0]], &b = m.vertices[f[1]], &c = m.vertices[f[2]];
    out.push_back({a.x(), a.y(), a.z(), b.x(), b.y(), b.z(), c.x(), c.y(), c.z()});
  }
  std::sort(out.begin(), out.end());
  return out;
}

// The copy holds the volume's mesh, triangle for triangle (the same floats).
void expectSameSurface(const BlockCopy& copy, fusion::TsdfVolume* volume) {
  const std::vector<Triangle> expected = meshTriangles(volume->extractMesh());
  const std::vector<Triangle> got = copy.triangles();
  EXPECT_EQ(got.size(), expected.size());
  EXPECT_TRUE(got == expected) << "the union of the blocks is not the mesh";
}

std::size_t blocksWithSurface(const BlockCopy& copy) { return copy.blocks.size(); }

fusion::TsdfConfig config() {
  fusion::TsdfConfig c;
  c.voxel_size = 0.03;
  c.truncation = 0.09;
  return c;
}

const Vector3d kA(0.0, 0.0, 0.0);
const Vector3d kB(3.0, 0.0, 0.0);  // a second sphere, far from the first

}  // namespace

TEST(TsdfBlocks, TheBlocksGivenAddUpToTheMeshAfterEveryUpdate) {
  const meshing::PinholeImage image = test::sphereTestImage();
  fusion::TsdfVolume volume(config());
  BlockCopy copy;
  const auto views = test::viewsAround(kA, 1.5);
  for (std::size_t k = 0; k < views.size(); ++k) {
    volume.integrateDepth(sphereDepth(kA, 0.4, views[k], image), views[k], image);
    if (k % 3 != 2) continue;
    const fusion::MeshBlockUpdate u = volume.takeChangedBlocks();
    EXPECT_EQ(u.replace_all, copy.updates == 0) << "only the first update replaces everything";
    copy.apply(u);
    expectSameSurface(copy, &volume);
  }
  // The views fused since the last update; extractMesh in between does not consume the changes.
  volume.extractMesh();
  copy.apply(volume.takeChangedBlocks());
  expectSameSurface(copy, &volume);
  ASSERT_GT(blocksWithSurface(copy), 50u);
  // Nothing fused since: nothing to send.
  EXPECT_TRUE(volume.takeChangedBlocks().blocks.empty());

  // A rescale moves every block: all given again, in the new place.
  volume.rescale(Vector3d(1.0, 0.5, 0.0), 1.07);
  const fusion::MeshBlockUpdate moved = volume.takeChangedBlocks();
  EXPECT_FALSE(moved.replace_all);
  EXPECT_EQ(moved.blocks.size(), blocksWithSurface(copy));
  copy.apply(moved);
  expectSameSurface(copy, &volume);

  // clear(): one update that replaces everything with nothing.
  volume.clear();
  const fusion::MeshBlockUpdate cleared = volume.takeChangedBlocks();
  EXPECT_TRUE(cleared.replace_all);
  EXPECT_TRUE(cleared.blocks.empty());
  copy.apply(cleared);
  EXPECT_TRUE(copy.blocks.empty());
}

// A view of the second sphere changes the blocks around it only: the update
// is a small part of the surface, and none of its blocks is near the first sphere.
TEST(TsdfBlocks, AnUpdateCarriesOnlyTheBlocksNearWhatWasFused) {
  const meshing::PinholeImage image = test::sphereTestImage();
  fusion::TsdfVolume volume(config());
  BlockCopy copy;
  for (const Vector3d& c : {kA, kB}) {
    for (const auto& T : test::viewsAround(c, 1.2)) volume.integrateDepth(sphereDepth(c, 0.4, T, image), T, image);
  }
  copy.apply(volume.takeChangedBlocks());
  const std::size_t all = blocksWithSurface(copy);
  const Isometry3d T = test::lookAt(kB + Vector3d(0.0, -1.0, 0.6), kB);
  volume.integrateDepth(sphereDepth(kB, 0.4, T, image), T, image);
  const fusion::MeshBlockUpdate u = volume.takeChangedBlocks();
  ASSERT_FALSE(u.blocks.empty());
  std::printf("[blocks] one view of the second sphere: %zu of %zu blocks changed\n", u.blocks.size(), all);
  EXPECT_LT(u.blocks.size(), all / 3) << "of " << all;
  const double block = config().voxel_size * config().block_voxels;
  for (const auto& b : u.blocks) {
    const Vector3d centre = (b.index.cast<double>().array() + 0.5).matrix() * block;
    EXPECT_LT((centre - kB).norm(), 0.4 + 2.0 * block) << b.index.transpose();
  }
  copy.apply(u);
  expectSameSurface(copy, &volume);
}

// A surface moved by later views (the wall 2 voxels farther, within the
// truncation band, so the old surface is overwritten): the block it leaves is
// given empty once, then never again; the copy still is the mesh.
TEST(TsdfBlocks, ABlockThatLosesItsSurfaceIsGivenEmptyOnce) {
  const meshing::PinholeImage image = test::sphereTestImage();
  fusion::TsdfConfig cfg = config();
  cfg.max_weight = 20.0;
  fusion::TsdfVolume volume(cfg);
  BlockCopy copy;
  const Isometry3d T = test::lookAt(Vector3d(0.0, 0.0, -1.5), kA);
  // A flat wall at depth d: every pixel.
  auto wall = [&](float d) { return std::vector<float>(static_cast<std::size_t>(image.width) * image.height, d); };
  volume.integrateDepth(wall(1.5f), T, image);
  copy.apply(volume.takeChangedBlocks());
  const std::size_t near_blocks = blocksWithSurface(copy);
  ASSERT_GT(near_blocks, 10u);
  for (int k = 0; k < 30; ++k) volume.integrateDepth(wall(1.56f), T, image);
  const fusion::MeshBlockUpdate u = volume.takeChangedBlocks();
  std::size_t emptied = 0;
  for (const auto& b : u.blocks) emptied += b.vertices.empty();
  EXPECT_GT(emptied, 0u);
  copy.apply(u);
  expectSameSurface(copy, &volume);
  for (int k = 0; k < 3; ++k) volume.integrateDepth(wall(1.56f), T, image);
  for (const auto& b : volume.takeChangedBlocks().blocks) EXPECT_FALSE(b.vertices.empty()) << "given empty twice";
}

// After a load the next update replaces everything with the file's surface.
TEST(TsdfBlocks, ALoadReplacesEverything) {
  const meshing::PinholeImage image = test::sphereTestImage();
  fusion::TsdfVolume saved(config()), volume(config());
  for (const auto& T : test::viewsAround(kA, 1.5)) saved.integrateDepth(sphereDepth(kA, 0.4, T, image), T, image);
  const Isometry3d T = test::lookAt(kB + Vector3d(0.0, 0.0, -1.2), kB);
  volume.integrateDepth(sphereDepth(kB, 0.4, T, image), T, image);
  BlockCopy copy;
  copy.apply(volume.takeChangedBlocks());
  ASSERT_FALSE(copy.blocks.empty());
  const std::string path = testing::TempDir() + "/ve_tsdf_blocks_" + std::to_string(::getpid()) + ".vetsdf";
  std::string error;
  ASSERT_TRUE(saved.save(path, &error)) << error;
  volume.load(path);
  std::remove(path.c_str());
  const fusion::MeshBlockUpdate u = volume.takeChangedBlocks();
  EXPECT_TRUE(u.replace_all);
  copy.apply(u);
  expectSameSurface(copy, &volume);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
