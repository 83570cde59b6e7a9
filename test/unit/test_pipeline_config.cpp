// The configuration table (src/pipeline/config_table.cpp) against the config
// structs: every member of every struct is a row (a yaml key, or marked as set
// internally), the printed config loads back to the same values, and
// docs/CONFIG.md is what the table generates.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cstddef>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "vitamin_e/camera/camera.h"
#include "vitamin_e/pipeline/system.h"
#include "vitamin_e/pipeline/system_config.h"

namespace pl = vitamin_e::pipeline;
namespace fs = std::filesystem;

namespace {

// The number of members of an aggregate: the largest N for which T{x1, ..., xN}
// compiles with x convertible to anything (a member that is itself an aggregate
// takes one x, as a whole). A new member raises it, so a struct that gains a
// field fails CoversEveryMemberOfEveryStruct until the table has a row for it.
struct AnyValue {
  template <typename T>
  operator T() const;  // declared only: used in unevaluated contexts
};

template <typename T, typename... A>
constexpr auto braceInitializable(int) -> decltype(T{std::declval<A>()...}, true) {
  return true;
}
template <typename T, typename... A>
constexpr bool braceInitializable(...) {
  return false;
}
template <typename T, std::size_t... I>
constexpr bool initializableWith(std::index_sequence<I...>) {
  return braceInitializable<T, decltype(static_cast<void>(I), AnyValue{})...>(0);
}
template <typename T, std::size_t N = 0>
constexpr std::size_t memberCount() {
  if constexpr (N < 128 && initializableWith<T>(std::make_index_sequence<N + 1>{})) {
    return memberCount<T, N + 1>();
  } else {
    return N;
  }
}

struct Probe {
  int a;
  double b;
  bool c;
};
struct NestedProbe {
  Probe p;
  int d = 3;
};
static_assert(memberCount<Probe>() == 3, "memberCount counts plain members");
static_assert(memberCount<NestedProbe>() == 2, "memberCount counts a nested aggregate as one member");

struct Region {
  std::ptrdiff_t begin, end;
  bool contains(std::ptrdiff_t o) const { return o >= begin && o < end; }
};

template <typename S>
Region regionOf(const pl::SystemConfig& c, const S& member) {
  const std::ptrdiff_t begin = reinterpret_cast<const char*>(&member) - reinterpret_cast<const char*>(&c);
  return {begin, begin + static_cast<std::ptrdiff_t>(sizeof(S))};
}

// Rows of the table pointing into `self` but not into one of its nested config structs.
std::size_t directMembersInTable(const std::set<std::ptrdiff_t>& offsets, const Region& self,
                                 const std::vector<Region>& nested) {
  std::size_t n = 0;
  for (std::ptrdiff_t o : offsets) {
    if (!self.contains(o)) continue;
    bool inside = false;
    for (const Region& r : nested) inside = inside || r.contains(o);
    if (!inside) ++n;
  }
  return n;
}

std::string readFile(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

class ConfigFile : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("ve_config_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string write(const std::string& text) {
    std::string p = (dir_ / ("c" + std::to_string(n_++) + ".yaml")).string();
    std::ofstream(p) << text;
    return p;
  }
  std::string loadError(const std::string& text) {
    try {
      pl::loadSystemConfig(write(text));
    } catch (const pl::ConfigError& e) {
      return e.what();
    }
    return "";
  }
  fs::path dir_;
  int n_ = 0;
};

}  // namespace

TEST(ConfigTable, CoversEveryMemberOfEveryStruct) {
  const pl::SystemConfig c;
  const std::vector<pl::ConfigField> table = pl::configFields(c);
  std::set<std::ptrdiff_t> offsets;
  for (const pl::ConfigField& f : table) {
    ASSERT_FALSE(f.offsets.empty()) << f.section << "." << f.key;
    for (std::ptrdiff_t o : f.offsets) {
      EXPECT_TRUE(offsets.insert(o).second) << f.section << "." << f.key << ": a member set by two rows";
    }
  }
  const auto& d = c.dense;
  const Region system = regionOf(c, c);
  const std::vector<Region> system_parts = {regionOf(c, c.tracker),        regionOf(c, c.init),   regionOf(c, c.pnp),
                                            regionOf(c, c.triangulation),  regionOf(c, c.ba),     regionOf(c, c.map),
                                            regionOf(c, c.relocalization), regionOf(c, c.ground), regionOf(c, c.dense)};
  const std::vector<Region> dense_parts = {regionOf(c, d.mesher), regionOf(c, d.prune), regionOf(c, d.nltgv),
                                           regionOf(c, d.integrator)};
  struct Expect {
    const char* name;
    std::size_t members;  // memberCount of the struct
    std::size_t rows;     // members with a row
  };
  const std::vector<Expect> structs = {
      {"pipeline::SystemConfig", memberCount<pl::SystemConfig>(),
       directMembersInTable(offsets, system, system_parts) + system_parts.size()},
      {"tracking::TrackerConfig", memberCount<vitamin_e::tracking::TrackerConfig>(),
       directMembersInTable(offsets, regionOf(c, c.tracker), {})},
      {"geometry::TwoViewConfig", memberCount<vitamin_e::geometry::TwoViewConfig>(),
       directMembersInTable(offsets, regionOf(c, c.init), {})},
      {"geometry::PnpConfig", memberCount<vitamin_e::geometry::PnpConfig>(),
       directMembersInTable(offsets, regionOf(c, c.pnp), {})},
      {"geometry::TriangulationConfig", memberCount<vitamin_e::geometry::TriangulationConfig>(),
       directMembersInTable(offsets, regionOf(c, c.triangulation), {})},
      {"optimization::BaOptions", memberCount<vitamin_e::optimization::BaOptions>(),
       directMembersInTable(offsets, regionOf(c, c.ba), {})},
      {"map::MapConfig", memberCount<vitamin_e::map::MapConfig>(),
       directMembersInTable(offsets, regionOf(c, c.map), {})},
      {"pipeline::RelocalizerConfig", memberCount<pl::RelocalizerConfig>(),
       directMembersInTable(offsets, regionOf(c, c.relocalization), {})},
      {"pipeline::GroundScaleConfig", memberCount<pl::GroundScaleConfig>(),
       directMembersInTable(offsets, regionOf(c, c.ground), {regionOf(c, c.ground.plane)}) + 1},
      {"geometry::GroundPlaneConfig", memberCount<vitamin_e::geometry::GroundPlaneConfig>(),
       directMembersInTable(offsets, regionOf(c, c.ground.plane), {})},
      {"fusion::DenseMapperConfig", memberCount<vitamin_e::fusion::DenseMapperConfig>(),
       directMembersInTable(offsets, regionOf(c, c.dense), dense_parts) + dense_parts.size()},
      {"meshing::FrameMesherConfig (dense mesher)", memberCount<vitamin_e::meshing::FrameMesherConfig>(),
       directMembersInTable(offsets, regionOf(c, d.mesher), {})},
      {"meshing::FrameMesherConfig (dense prune)", memberCount<vitamin_e::meshing::FrameMesherConfig>(),
       directMembersInTable(offsets, regionOf(c, d.prune), {})},
      {"meshing::NltgvConfig", memberCount<vitamin_e::meshing::NltgvConfig>(),
       directMembersInTable(offsets, regionOf(c, d.nltgv), {})},
      {"fusion::TsdfIntegratorConfig", memberCount<vitamin_e::fusion::TsdfIntegratorConfig>(),
       directMembersInTable(offsets, regionOf(c, d.integrator), {regionOf(c, d.integrator.tsdf)}) + 1},
      {"fusion::TsdfConfig", memberCount<vitamin_e::fusion::TsdfConfig>(),
       directMembersInTable(offsets, regionOf(c, d.integrator.tsdf), {})},
  };
  for (const Expect& e : structs) {
    EXPECT_EQ(e.rows, e.members) << e.name << " has " << e.members << " members and the table (src/pipeline/"
                                 << "config_table.cpp) covers " << e.rows
                                 << ": add a row for the new member (a key, or internal)";
  }
  // Every offset lies in one of the structs above.
  for (std::ptrdiff_t o : offsets) EXPECT_TRUE(system.contains(o)) << o;
}

TEST(ConfigTable, KeysAreUniqueAndDescribed) {
  std::set<std::string> keys;
  for (const pl::ConfigField& f : pl::configFields(pl::SystemConfig{})) {
    EXPECT_TRUE(keys.insert(f.section + "." + f.key).second) << "duplicate " << f.section << "." << f.key;
    EXPECT_TRUE(!f.description.empty() || !f.internal.empty()) << f.section << "." << f.key << " has no description";
    EXPECT_EQ(f.description.find('\n'), std::string::npos) << f.section << "." << f.key;
  }
}

TEST(ConfigTable, ReferenceDocIsCurrent) {
  const fs::path doc = fs::path(VITAMIN_E_SOURCE_DIR) / "docs" / "CONFIG.md";
  ASSERT_TRUE(fs::exists(doc)) << doc;
  EXPECT_TRUE(readFile(doc) == pl::configReferenceMarkdown())
      << doc << " is stale: regenerate it with\n  .ws/devel/lib/vitamin_e/vitamin_e_run --print-config-markdown > "
      << "docs/CONFIG.md";
}

TEST_F(ConfigFile, PrintedConfigLoadsBackToTheSameValues) {
  // Every settable value changed from its default (where validation allows), printed, loaded again.
  pl::SystemConfig c;
  c.tracker.brief_scale = 1.0 / 7.0;
  c.tracker.refine_flow = false;
  c.tracker.max_curvature_ratio = 1.7;
  c.ba.camera_solver = vitamin_e::optimization::BaOptions::CameraSolver::kGaussSeidel;
  c.ba.point_tolerance = 1e-4;
  c.map.max_archive_points = 123456;
  c.dense.nltgv.beta = 0.125;
  c.dense_enabled = false;
  c.reuse_radius_px = 0.1 + 0.2;  // not a short decimal
  const std::string printed = c.describe();
  const pl::SystemConfig back = pl::loadSystemConfig(write(printed));
  EXPECT_EQ(back.describe(), printed);
  EXPECT_EQ(back.tracker.brief_scale, c.tracker.brief_scale);
  EXPECT_EQ(back.reuse_radius_px, c.reuse_radius_px);
  EXPECT_EQ(back.ba.camera_solver, c.ba.camera_solver);
  EXPECT_FALSE(back.tracker.refine_flow);
  // Every row is printed: a key as "key: value", an internal member as a comment.
  for (const pl::ConfigField& f : pl::configFields(c)) {
    const std::string line = f.internal.empty() ? "  " + f.key + ": " + f.value + "\n" : "  # " + f.key + ": ";
    EXPECT_NE(printed.find(line), std::string::npos) << f.section << "." << f.key;
  }
}

TEST_F(ConfigFile, EveryKeyIsReadFromTheYaml) {
  // Each key alone, at its printed default: accepted; and each one is a key that existed in the table.
  for (const pl::ConfigField& f : pl::configFields(pl::SystemConfig{})) {
    if (!f.internal.empty()) continue;
    EXPECT_EQ(loadError(f.section + ":\n  " + f.key + ": " + f.value + "\n"), "") << f.section << "." << f.key;
  }
  const pl::SystemConfig c =
      pl::loadSystemConfig(write("tracker:\n  max_curvature_ratio: 2.5\n  align_iterations: 3\n  refine_flow: false\n"
                                 "ba:\n  camera_solver: gauss_seidel\n  point_extrapolation: 4\n"
                                 "dense:\n  nltgv_alpha: 2.0\n  block_voxels: 16\n  mesh_max_edge_px: 33\n"));
  EXPECT_EQ(c.tracker.max_curvature_ratio, 2.5);
  EXPECT_EQ(c.tracker.align_iterations, 3);
  EXPECT_FALSE(c.tracker.refine_flow);
  EXPECT_EQ(c.ba.camera_solver, vitamin_e::optimization::BaOptions::CameraSolver::kGaussSeidel);
  EXPECT_EQ(c.ba.point_extrapolation, 4);
  EXPECT_EQ(c.dense.nltgv.alpha, 2.0);
  EXPECT_EQ(c.dense.integrator.tsdf.block_voxels, 16);
  EXPECT_EQ(c.dense.mesher.max_edge_px, 33.0);
}

TEST_F(ConfigFile, DenseDepthRangeIsOneSetting) {
  // dense.max_depth limits the meshed points and the fused depths alike (runner and meshing nodelet).
  const pl::SystemConfig c = pl::loadSystemConfig(write("dense:\n  min_depth: 0.2\n  max_depth: 4.5\n"));
  EXPECT_EQ(c.dense.mesher.max_depth, 4.5);
  EXPECT_EQ(c.dense.prune.max_depth, 4.5);
  EXPECT_EQ(c.dense.integrator.tsdf.max_depth, 4.5);
  EXPECT_EQ(c.dense.mesher.min_depth, 0.2);
  EXPECT_EQ(c.dense.prune.min_depth, 0.2);
  EXPECT_EQ(c.dense.integrator.tsdf.min_depth, 0.2);
  const pl::SystemConfig defaults;
  EXPECT_EQ(defaults.dense.mesher.max_depth, defaults.dense.integrator.tsdf.max_depth);
  EXPECT_EQ(defaults.dense.mesher.min_depth, defaults.dense.integrator.tsdf.min_depth);
}

TEST_F(ConfigFile, InternalMembersAndBadValuesAreRefusedByName) {
  for (const char* const key : {"init:\n  focal_px: 400\n", "pnp:\n  focal_px: 400\n", "ba:\n  max_sweeps: 5\n",
                                "pipeline:\n  min_init_tracks: 200\n", "ground:\n  min_inliers: 100\n"}) {
    const std::string err = loadError(key);
    EXPECT_NE(err.find("cannot be set"), std::string::npos) << key << " -> " << err;
  }
  std::string err = loadError("ba:\n  camera_solver: cholesky\n");
  EXPECT_NE(err.find("ba.camera_solver"), std::string::npos) << err;
  EXPECT_NE(err.find("conjugate_gradient"), std::string::npos) << err;
  err = loadError("tracker:\n  align_iterations: 0\n");
  EXPECT_NE(err.find("tracker"), std::string::npos) << err;
  EXPECT_NE(err.find("align_iterations"), std::string::npos) << err;
  err = loadError("dense:\n  nltgv_theta: 1.5\n");
  EXPECT_NE(err.find("dense"), std::string::npos) << err;
  EXPECT_NE(err.find("theta"), std::string::npos) << err;
  err = loadError("dense:\n  max_depth: 0.01\n");  // below min_depth
  EXPECT_NE(err.find("max_depth"), std::string::npos) << err;
}

TEST(ConfigTable, CountsOfPointsFollowThePointBudget) {
  // A camera tracking a quarter of the points asks for a quarter of the tracks to initialize and
  // of the road points; a tiny budget keeps the floors an essential matrix and a plane need.
  const vitamin_e::camera::Camera camera(752, 480, 458.0, 457.0, 367.0, 248.0);
  pl::SystemConfig config;
  const auto resolved = [&](int max_points) {
    config.tracker.max_points = max_points;
    const pl::System system(config, camera);
    return std::make_pair(system.config().min_init_tracks, system.config().ground.plane.min_inliers);
  };
  EXPECT_EQ(resolved(8000), std::make_pair(200, 100));
  EXPECT_EQ(resolved(2000), std::make_pair(50, 25));
  EXPECT_EQ(resolved(100), std::make_pair(pl::kMinInitTracksFloor, pl::kMinRoadInliersFloor));
  config.min_init_track_budget_fraction = 0.05;
  config.ground.min_inlier_budget_fraction = 0.01;
  EXPECT_EQ(resolved(6000), std::make_pair(300, 60));
}

TEST(ConfigFiles, ShippedSlamConfigsLoad) {
  // The SLAM configs in config/ (launch files and scripts name them): every key known, every
  // value valid. webcam.yaml is euroc.yaml with the changes its comments state.
  const fs::path dir = fs::path(VITAMIN_E_SOURCE_DIR) / "config";
  std::map<std::string, pl::SystemConfig> loaded;
  for (const char* name : {"euroc.yaml", "kitti.yaml", "tum.yaml", "webcam.yaml"}) {
    ASSERT_TRUE(fs::exists(dir / name)) << dir / name;
    try {
      loaded[name] = pl::loadSystemConfig((dir / name).string());
    } catch (const pl::ConfigError& e) {
      ADD_FAILURE() << name << ": " << e.what();
    }
  }
  // One keyframe retirement rule for every camera (issue 23): no shipped config opts out of it.
  for (const auto& [name, config] : loaded) {
    EXPECT_TRUE(config.map.retire_least_parallax) << name << " retires its keyframes by another rule";
  }
  ASSERT_EQ(loaded.count("webcam.yaml"), 1u);
  const pl::SystemConfig& w = loaded["webcam.yaml"];
  EXPECT_EQ(w.tracker.max_points, 6800);
  EXPECT_EQ(w.pnp.ransac_threshold_px, 3.0);
  EXPECT_EQ(w.ba.robust_sigma_px, 3.0);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
