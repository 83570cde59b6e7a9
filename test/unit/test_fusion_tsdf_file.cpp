// TsdfVolume::save / load: a sphere fused from depth maps is saved and loaded
// into a fresh volume with every voxel and the same mesh; a loaded volume goes
// on fusing; files of another grid, damaged or foreign files are refused with
// a TsdfFileError naming the file, and leave the volume as it was.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <sstream>

#include "sphere_views.h"
#include "vitamin_e/fusion/dense_mapper.h"
#include "vitamin_e/fusion/tsdf_volume.h"

using namespace vitamin_e;
using Eigen::Isometry3d;
using Eigen::Vector3d;
namespace fs = std::filesystem;

namespace {

meshing::PinholeImage smallImage() { return test::sphereTestImage(); }
Isometry3d lookAtOrigin(const Vector3d& eye) { return test::lookAt(eye, Vector3d::Zero()); }
std::vector<float> sphereDepth(double r, const Isometry3d& T_w_c, const meshing::PinholeImage& image) {
  return test::sphereDepth(Vector3d::Zero(), r, T_w_c, image);
}

fusion::TsdfConfig config() {
  fusion::TsdfConfig c;
  c.voxel_size = 0.02;
  c.truncation = 0.06;
  return c;
}

void fuse(fusion::TsdfVolume* volume, const std::vector<Vector3d>& eyes) {
  for (const Vector3d& eye : eyes) {
    const Isometry3d T = lookAtOrigin(eye);
    volume->integrateDepth(sphereDepth(0.4, T, smallImage()), T, smallImage());
  }
}

std::map<std::tuple<long, long, long>, fusion::Voxel> voxels(const fusion::TsdfVolume& v) {
  std::map<std::tuple<long, long, long>, fusion::Voxel> out;
  v.forEachVoxel([&](const Vector3d& p, const fusion::Voxel& x) {
    out[{std::lround(p.x() / 0.01), std::lround(p.y() / 0.01), std::lround(p.z() / 0.01)}] = x;
  });
  return out;
}

std::string readAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

void writeAll(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary | std::ios::trunc)
      .write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

struct Dir {
  fs::path path = fs::temp_directory_path() / ("ve_tsdf_file_" + std::to_string(::getpid()));
  Dir() { fs::create_directories(path); }
  ~Dir() { fs::remove_all(path); }
  std::string file(const std::string& n) const { return (path / n).string(); }
};

const std::vector<Vector3d> kFront = {Vector3d(1.5, 0.2, 0.3), Vector3d(1.4, -0.4, 0.2), Vector3d(1.2, 0.5, -0.6)};
const std::vector<Vector3d> kBack = {Vector3d(-1.5, 0.1, 0.2), Vector3d(-1.3, -0.5, 0.4)};

}  // namespace

TEST(TsdfFile, SavedAndLoadedVolumeHasEveryVoxelAndTheSameMesh) {
  Dir dir;
  fusion::TsdfVolume a(config());
  fuse(&a, kFront);
  ASSERT_GT(a.numBlocks(), 20u);
  const std::string path = dir.file("sphere.vetsdf");
  std::string error;
  ASSERT_TRUE(a.save(path, &error)) << error;
  const std::string bytes = readAll(path);
  EXPECT_EQ(bytes.substr(0, bytes.find('\n')),
            "vitamin_e tsdf v1, " + std::to_string(a.numBlocks()) + " blocks, voxel 0.02, 8^3 voxels per block");

  fusion::TsdfVolume b(config());
  b.load(path);
  EXPECT_EQ(b.numBlocks(), a.numBlocks());
  const auto va = voxels(a), vb = voxels(b);
  ASSERT_EQ(va.size(), vb.size());
  for (const auto& [key, v] : va) {
    const auto it = vb.find(key);
    ASSERT_NE(it, vb.end());
    EXPECT_EQ(v.sdf, it->second.sdf);
    EXPECT_EQ(v.weight, it->second.weight);
  }
  const fusion::TriangleMesh ma = a.extractMesh(), mb = b.extractMesh();
  EXPECT_GT(ma.faces.size(), 500u);
  EXPECT_EQ(ma.vertices.size(), mb.vertices.size());
  EXPECT_EQ(ma.faces.size(), mb.faces.size());
  // Saved again: the same bytes.
  ASSERT_TRUE(b.save(dir.file("again.vetsdf")));
  EXPECT_TRUE(readAll(dir.file("again.vetsdf")) == bytes);
}

TEST(TsdfFile, ALoadedVolumeGoesOnFusingLikeTheOriginal) {
  Dir dir;
  fusion::TsdfVolume whole(config()), first(config());
  fuse(&whole, kFront);
  fuse(&first, kFront);
  ASSERT_TRUE(first.save(dir.file("front.vetsdf")));
  fusion::TsdfVolume later(config());
  later.load(dir.file("front.vetsdf"));
  fuse(&whole, kBack);
  fuse(&later, kBack);
  EXPECT_EQ(later.numBlocks(), whole.numBlocks());
  EXPECT_EQ(later.extractMesh().faces.size(), whole.extractMesh().faces.size());
}

TEST(TsdfFile, ADenseMapperSavesAndLoadsItsVolume) {
  Dir dir;
  fusion::DenseMapperConfig c;
  c.integrator.tsdf = config();
  c.integrator.asynchronous = false;
  fusion::DenseMapper empty(c, smallImage());
  EXPECT_TRUE(empty.saveTsdf(dir.file("empty.vetsdf")));  // no block: a valid, empty file
  fusion::TsdfVolume source(config());
  fuse(&source, kFront);
  ASSERT_TRUE(source.save(dir.file("sphere.vetsdf")));
  fusion::DenseMapper mapper(c, smallImage());
  mapper.loadTsdf(dir.file("sphere.vetsdf"));
  EXPECT_EQ(mapper.extractMesh().faces.size(), source.extractMesh().faces.size());
  mapper.loadTsdf(dir.file("empty.vetsdf"));
  EXPECT_TRUE(mapper.extractMesh().faces.empty());
}

TEST(TsdfFile, OtherGridsAndDamagedFilesAreRefusedAndLeaveTheVolume) {
  Dir dir;
  fusion::TsdfVolume a(config());
  fuse(&a, kFront);
  const std::string path = dir.file("sphere.vetsdf");
  ASSERT_TRUE(a.save(path));
  const std::string bytes = readAll(path);

  fusion::TsdfVolume target(config());
  fuse(&target, kBack);
  const std::size_t blocks = target.numBlocks();
  auto refused = [&](const std::string& file, const std::string& words) {
    try {
      target.load(file);
      ADD_FAILURE() << file << " was accepted";
    } catch (const fusion::TsdfFileError& e) {
      EXPECT_NE(std::string(e.what()).find(file), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
    }
    EXPECT_EQ(target.numBlocks(), blocks);
  };
  fusion::TsdfConfig coarse = config();
  coarse.voxel_size = 0.04;
  coarse.truncation = 0.12;
  fusion::TsdfVolume other(coarse);
  fuse(&other, kFront);
  ASSERT_TRUE(other.save(dir.file("coarse.vetsdf")));
  refused(dir.file("coarse.vetsdf"), "voxel 0.04");
  refused(dir.file("missing.vetsdf"), "No such file");
  writeAll(dir.file("empty.vetsdf"), "");
  refused(dir.file("empty.vetsdf"), "empty");
  writeAll(dir.file("map.vetsdf"), "vitamin_e map v1, 3 keyframes, 10 points, camera 752x480\n");
  refused(dir.file("map.vetsdf"), "not a vitamin_e TSDF file");
  writeAll(dir.file("cut.vetsdf"), bytes.substr(0, bytes.size() - 100));
  refused(dir.file("cut.vetsdf"), "truncated");
  std::mt19937 rng(5);
  std::uniform_int_distribution<std::size_t> pos(0, bytes.size() - 1);
  for (int trial = 0; trial < 60; ++trial) {
    std::string flipped = bytes;
    const std::size_t at = pos(rng);
    flipped[at] = static_cast<char>(flipped[at] ^ static_cast<char>(1 << (trial % 8)));
    writeAll(dir.file("flip.vetsdf"), flipped);
    refused(dir.file("flip.vetsdf"), "");
    writeAll(dir.file("cut.vetsdf"), bytes.substr(0, pos(rng)));
    refused(dir.file("cut.vetsdf"), "");
  }
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
