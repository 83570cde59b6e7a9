// The map file (map/map_file.h) and Map::snapshot / Map::restore: a map built
// through the Map's own methods (keyframes retired into dormant landmarks and
// the archive) round-trips through a file exactly, the first line is readable,
// and every damaged file (missing, empty, foreign, truncated, a flipped byte,
// another version, a header that does not match its data) gives one
// MapFileError naming the file, never a crash.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>

#include "vitamin_e/map/map.h"
#include "vitamin_e/map/map_file.h"

namespace ve = vitamin_e;
namespace fs = std::filesystem;
using ve::map::MapFileContents;
using ve::map::MapFileError;

namespace {

class TempDir {
 public:
  TempDir() {
    path_ = fs::temp_directory_path() / ("ve_map_file_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
    fs::create_directories(path_);
  }
  ~TempDir() { fs::remove_all(path_); }
  std::string file(const std::string& name) const { return (path_ / name).string(); }
  const fs::path& path() const { return path_; }

 private:
  static inline int counter = 0;
  fs::path path_;
};

std::string readAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

void writeAll(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

Eigen::Isometry3d poseAt(double x, double yaw) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(x, 0.1 * x, 0.0);
  return T;
}

// A map grown through its methods: 12 keyframes through a window of 4, each
// seeing 60 tracks (30 shared with the previous keyframe), a landmark per
// track, so that retired keyframes leave dormant landmarks and archived points.
ve::map::Map grownMap() {
  ve::map::MapConfig config;
  config.max_keyframes = 4;
  config.min_observations_to_archive = 2;
  ve::map::Map map(config);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int k = 0; k < 12; ++k) {
    ve::map::Keyframe kf;
    kf.frame_index = 10 + 5 * static_cast<std::uint64_t>(k);
    kf.timestamp = 100.0 + 0.25 * k;
    kf.T_w_c = poseAt(0.2 * k, 0.05 * k);
    for (int i = 0; i < 60; ++i) {
      const std::uint64_t id = 30 * static_cast<std::uint64_t>(k) + static_cast<std::uint64_t>(i) + 1;
      kf.observations.emplace(id, Eigen::Vector2d(u(rng), u(rng)));
    }
    map.addKeyframe(kf);
    for (int i = 30; i < 60; ++i) {
      ve::map::NewLandmark l;
      l.id = 30 * static_cast<std::uint64_t>(k) + static_cast<std::uint64_t>(i) + 1;
      l.p_w = Eigen::Vector3d(u(rng), u(rng), 2.0 + u(rng));
      l.intensity = static_cast<std::uint8_t>(i * 4);
      l.polarity = i % 2 ? 1 : -1;
      l.seen_frame = kf.frame_index;
      l.prior_observations = 1;
      map.addLandmark(l);
    }
    map.flagOutlier(30 * static_cast<std::uint64_t>(k) + 45);
  }
  return map;
}

MapFileContents contentsOf(const ve::map::Map& map) {
  MapFileContents c;
  c.camera =
      ve::camera::Camera(752, 480, 458.654, 457.296, 367.215, 248.375, ve::camera::DistortionModel::kRadialTangential,
                         {-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05});
  c.scale_convention = "test";
  c.scene_depth = 1.7;
  c.descriptors = {31, 2.0};
  c.map = map.snapshot();
  std::mt19937_64 rng(3);
  for (int k = 0; k < 5; ++k) {
    ve::map::IndexedKeyframe kf;
    kf.frame_index = 10 + 5 * static_cast<std::uint64_t>(k);
    kf.T_w_c = poseAt(0.2 * k, 0.05 * k);
    for (int i = 0; i < 40; ++i) {
      ve::map::IndexedPoint p;
      p.landmark_id = 30 * static_cast<std::uint64_t>(k) + static_cast<std::uint64_t>(i) + 1;
      p.p_w = Eigen::Vector3d(0.01 * i, -0.02 * i, 2.0 + 0.001 * i);
      for (auto& b : p.descriptor) b = rng();
      p.polarity = i % 3 == 0 ? 1 : -1;
      kf.points.push_back(p);
    }
    c.keyframe_index.push_back(kf);
  }
  return c;
}

void expectSamePose(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  EXPECT_TRUE(a.matrix() == b.matrix()) << a.matrix() << "\nvs\n" << b.matrix();
}

void expectSameMaps(const ve::map::Map& a, const ve::map::Map& b) {
  ASSERT_EQ(a.keyframes().size(), b.keyframes().size());
  for (std::size_t k = 0; k < a.keyframes().size(); ++k) {
    const auto& x = a.keyframes()[k];
    const auto& y = b.keyframes()[k];
    EXPECT_EQ(x.frame_index, y.frame_index);
    EXPECT_EQ(x.timestamp, y.timestamp);
    expectSamePose(x.T_w_c, y.T_w_c);
    EXPECT_EQ(x.observations, y.observations);
  }
  ASSERT_EQ(a.landmarks().size(), b.landmarks().size());
  for (const auto& kv : a.landmarks()) {
    const ve::map::Landmark* l = b.landmark(kv.first);
    ASSERT_NE(l, nullptr) << "landmark " << kv.first;
    const ve::map::Landmark& m = kv.second;
    EXPECT_TRUE(m.p_w == l->p_w);
    EXPECT_EQ(m.intensity, l->intensity);
    EXPECT_EQ(m.polarity, l->polarity);
    EXPECT_EQ(m.revived, l->revived);
    EXPECT_EQ(m.num_observations, l->num_observations);
    EXPECT_EQ(m.last_seen_frame, l->last_seen_frame);
    EXPECT_EQ(m.outlier_count, l->outlier_count);
    ASSERT_EQ(m.observations.size(), l->observations.size()) << "landmark " << kv.first;
    for (std::size_t i = 0; i < m.observations.size(); ++i) {
      EXPECT_EQ(m.observations[i].keyframe, l->observations[i].keyframe);
      EXPECT_TRUE(m.observations[i].xy == l->observations[i].xy);
    }
  }
  ASSERT_EQ(a.dormant().size(), b.dormant().size());
  for (std::size_t i = 0; i < a.dormant().size(); ++i) {
    EXPECT_EQ(a.dormant()[i].id, b.dormant()[i].id);
    EXPECT_TRUE(a.dormant()[i].p_w == b.dormant()[i].p_w);
    EXPECT_EQ(a.dormant()[i].revived, b.dormant()[i].revived);
  }
  EXPECT_EQ(a.dormantDropped(), b.dormantDropped());
  ASSERT_EQ(a.archive().size(), b.archive().size());
  for (std::size_t i = 0; i < a.archive().size(); ++i) EXPECT_TRUE(a.archive()[i].p_w == b.archive()[i].p_w);
  EXPECT_EQ(a.archiveVoxel(), b.archiveVoxel());
}

// A file of the grown map, written once per test.
struct SavedMap {
  TempDir dir;
  std::string path = dir.file("room.vemap");
  MapFileContents contents = contentsOf(grownMap());
  std::string bytes;
  SavedMap() {
    std::string error;
    EXPECT_TRUE(ve::map::saveMapFile(contents, path, &error)) << error;
    bytes = readAll(path);
  }
};

void expectRefused(const std::string& path, const std::string& expected_words) {
  try {
    ve::map::loadMapFile(path);
    ADD_FAILURE() << path << " was accepted (expected: " << expected_words << ")";
  } catch (const MapFileError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(path), std::string::npos) << what;
    EXPECT_NE(what.find(expected_words), std::string::npos) << what;
  }
}

}  // namespace

TEST(MapSnapshot, RestoreGivesTheSameMapIncludingObservationsAndDormantPoints) {
  const ve::map::Map map = grownMap();
  ASSERT_EQ(map.keyframes().size(), 4u);
  ASSERT_GT(map.dormant().size(), 50u);
  ASSERT_GT(map.archive().size(), 50u);
  ve::map::MapConfig config;
  config.max_keyframes = 4;
  config.min_observations_to_archive = 2;
  ve::map::Map restored(config);
  restored.restore(map.snapshot());
  expectSameMaps(map, restored);
}

TEST(MapSnapshot, RestoreRefusesAnInconsistentSnapshotAndKeepsTheMap) {
  ve::map::Map map = grownMap();
  ve::map::MapSnapshot bad = map.snapshot();
  std::swap(bad.keyframes[0], bad.keyframes[1]);  // out of order
  const std::size_t landmarks = map.landmarks().size();
  EXPECT_THROW(map.restore(bad), std::invalid_argument);
  bad = map.snapshot();
  bad.landmarks.push_back(bad.landmarks.front());  // a duplicate id
  EXPECT_THROW(map.restore(bad), std::invalid_argument);
  bad = map.snapshot();
  bad.landmarks[3].p_w.x() = std::nan("");
  EXPECT_THROW(map.restore(bad), std::invalid_argument);
  EXPECT_EQ(map.landmarks().size(), landmarks);
  EXPECT_EQ(map.keyframes().size(), 4u);
}

TEST(MapSnapshot, RestoreUnderASmallerWindowRetiresTheOldestKeyframes) {
  const ve::map::Map map = grownMap();
  ve::map::MapConfig config;
  config.max_keyframes = 2;
  config.min_observations_to_archive = 2;
  ve::map::Map restored(config);
  restored.restore(map.snapshot());
  ASSERT_EQ(restored.keyframes().size(), 2u);
  EXPECT_EQ(restored.keyframes().front().frame_index, map.keyframes()[2].frame_index);
  EXPECT_GT(restored.dormant().size(), map.dormant().size());
}

TEST(MapFile, RoundTripIsExactAndSavingAgainGivesTheSameBytes) {
  SavedMap saved;
  const MapFileContents loaded = ve::map::loadMapFile(saved.path);
  ve::map::MapConfig config;
  config.max_keyframes = 4;
  config.min_observations_to_archive = 2;
  ve::map::Map a(config), b(config);
  a.restore(saved.contents.map);
  b.restore(loaded.map);
  expectSameMaps(a, b);
  EXPECT_EQ(loaded.camera.describe(), saved.contents.camera.describe());
  EXPECT_EQ(loaded.camera.distortion(), saved.contents.camera.distortion());
  EXPECT_EQ(loaded.scene_depth, saved.contents.scene_depth);
  EXPECT_EQ(loaded.scale_convention, saved.contents.scale_convention);
  EXPECT_EQ(loaded.descriptors.patch_size, 31);
  ASSERT_EQ(loaded.keyframe_index.size(), saved.contents.keyframe_index.size());
  for (std::size_t k = 0; k < loaded.keyframe_index.size(); ++k) {
    const auto& x = loaded.keyframe_index[k];
    const auto& y = saved.contents.keyframe_index[k];
    EXPECT_EQ(x.frame_index, y.frame_index);
    expectSamePose(x.T_w_c, y.T_w_c);
    ASSERT_EQ(x.points.size(), y.points.size());
    for (std::size_t i = 0; i < x.points.size(); ++i) {
      EXPECT_EQ(x.points[i].landmark_id, y.points[i].landmark_id);
      EXPECT_TRUE(x.points[i].p_w == y.points[i].p_w);
      EXPECT_EQ(x.points[i].descriptor, y.points[i].descriptor);
      EXPECT_EQ(x.points[i].polarity, y.points[i].polarity);
    }
  }
  // Saved again from the restored map: byte for byte the same file.
  MapFileContents again = loaded;
  again.map = b.snapshot();
  const std::string path2 = saved.dir.file("again.vemap");
  ASSERT_TRUE(ve::map::saveMapFile(again, path2));
  EXPECT_TRUE(readAll(path2) == saved.bytes);
}

TEST(MapFile, FirstLineIsReadable) {
  SavedMap saved;
  const std::string first = saved.bytes.substr(0, saved.bytes.find('\n'));
  std::size_t points = saved.contents.map.landmarks.size();
  for (const auto& d : saved.contents.map.dormant) points += d.revived ? 0 : 1;
  // Keyframes: the window (4, frames 65..80) and the index (5, frames 10..30) are distinct.
  EXPECT_EQ(first, "vitamin_e map v1, 9 keyframes, " + std::to_string(points) + " points, camera 752x480");
}

TEST(MapFile, AWriteReplacesTheFileAndLeavesNoTemporaryFile) {
  SavedMap saved;
  MapFileContents smaller = saved.contents;
  smaller.keyframe_index.pop_back();
  ASSERT_TRUE(ve::map::saveMapFile(smaller, saved.path));
  EXPECT_EQ(ve::map::loadMapFile(saved.path).keyframe_index.size(), smaller.keyframe_index.size());
  std::size_t files = 0;
  for (const auto& e : fs::directory_iterator(saved.dir.path())) {
    ++files;
    EXPECT_EQ(e.path().filename(), "room.vemap");
  }
  EXPECT_EQ(files, 1u);
  // An unwritable place: an error, and nothing half written.
  std::string error;
  EXPECT_FALSE(ve::map::saveMapFile(saved.contents, saved.dir.file("no/such/dir/map.vemap"), &error));
  EXPECT_NE(error.find("no/such/dir"), std::string::npos) << error;
}

TEST(MapFile, MissingEmptyForeignAndOtherVersionFilesAreRefusedByName) {
  SavedMap saved;
  expectRefused(saved.dir.file("missing.vemap"), "No such file");
  const std::string empty = saved.dir.file("empty.vemap");
  writeAll(empty, "");
  expectRefused(empty, "empty");
  const std::string foreign = saved.dir.file("foreign.vemap");
  writeAll(foreign, "ply\nformat binary_little_endian 1.0\nelement vertex 3\n");
  expectRefused(foreign, "not a vitamin_e map file");
  std::string v2 = saved.bytes;
  v2[15] = '2';  // "vitamin_e map v2, ..."
  const std::string other = saved.dir.file("v2.vemap");
  writeAll(other, v2);
  expectRefused(other, "format v2 is not supported");
  std::string no_version = saved.bytes;
  no_version[15] = 'x';  // "vitamin_e map vx, ..."
  const std::string damaged = saved.dir.file("vx.vemap");
  writeAll(damaged, no_version);
  expectRefused(damaged, "damaged header line");
  std::string lying = saved.bytes;
  lying.replace(lying.find(" 9 keyframes"), 12, " 8 keyframes");
  const std::string liar = saved.dir.file("liar.vemap");
  writeAll(liar, lying);
  expectRefused(liar, "does not describe its data");
  const std::string extra = saved.dir.file("extra.vemap");
  writeAll(extra, saved.bytes + "xyz");
  expectRefused(extra, "unknown data after");
}

TEST(MapFile, TruncatedFilesAreRefused) {
  SavedMap saved;
  const std::string path = saved.dir.file("cut.vemap");
  const std::size_t eol = saved.bytes.find('\n');
  for (std::size_t cut :
       {std::size_t{5}, eol, eol + 1, eol + 9, eol + 17, eol + 100, saved.bytes.size() / 2, saved.bytes.size() - 1}) {
    writeAll(path, saved.bytes.substr(0, cut));
    expectRefused(path, "");
  }
  writeAll(path, saved.bytes.substr(0, saved.bytes.size() / 2));
  expectRefused(path, "truncated");
}

TEST(MapFile, RandomTruncationsAndByteFlipsNeverPassOrCrash) {
  SavedMap saved;
  const std::string path = saved.dir.file("fuzz.vemap");
  std::mt19937 rng(12345);
  std::uniform_int_distribution<std::size_t> pos(0, saved.bytes.size() - 1);
  std::uniform_int_distribution<int> bit(0, 7);
  for (int trial = 0; trial < 150; ++trial) {
    writeAll(path, saved.bytes.substr(0, pos(rng)));
    EXPECT_THROW(ve::map::loadMapFile(path), MapFileError) << "truncation trial " << trial;
  }
  for (int trial = 0; trial < 300; ++trial) {
    std::string flipped = saved.bytes;
    // Flips anywhere, a third of them in the readable line and the sizes.
    const std::size_t at = trial % 3 == 0 ? pos(rng) % (saved.bytes.find('\n') + 17) : pos(rng);
    flipped[at] = static_cast<char>(flipped[at] ^ (1 << bit(rng)));
    writeAll(path, flipped);
    EXPECT_THROW(ve::map::loadMapFile(path), MapFileError) << "flip at byte " << at;
  }
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
