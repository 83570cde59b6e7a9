// Map persistence end to end on the project's own renders (376x240, the
// textured-wall trip of wall_trip.h): a first run maps the whole trip and saves
// the map; a second run over another render of the same room (other noise)
// that starts 1.7 m from where the first started loads it and
//  - in localization-only mode: is found by the relocalizer (no
//    initialization), localizes every frame after the first few, in the first
//    run's world frame and scale (the first run's Sim(3) to ground truth
//    applied unchanged gives a small error), adds no keyframe and no point and
//    leaves the file as it was;
//  - in extend mode: adds keyframes after the loaded ones, and its map saved,
//    loaded and saved again gives the same file.
// A map from another camera size is refused by name.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>

#include "vitamin_e/eval/metrics.h"
#include "vitamin_e/map/map_file.h"
#include "vitamin_e/pipeline/pipelined_system.h"
#include "vitamin_e/pipeline/system.h"
#include "vitamin_e/synth/renderer.h"
#include "vitamin_e/synth/scene.h"
#include "vitamin_e/synth/sequence.h"
#include "wall_trip.h"

namespace ve = vitamin_e;
namespace fs = std::filesystem;
using ve::pipeline::TrackingState;

namespace {

constexpr int kWidth = 376;
constexpr int kHeight = 240;
constexpr double kRate = 20.0;
constexpr int kFrames = 200;      // the whole trip: out 5 m in 5 s and back
constexpr int kSecondStart = 40;  // the second run starts here: 1.73 m from the first run's start
constexpr int kSecondFrames = 100;
constexpr double kT0 = 50.0;

Eigen::Isometry3d cameraPose(double t) { return ve::test::wallTripPose(t, kFrames / kRate, 5.0, -0.4); }

struct World {
  ve::camera::Camera camera = ve::synth::makeSequenceCamera(kWidth, kHeight, true);
  ve::synth::Scene scene;
  std::unique_ptr<ve::synth::Renderer> renderer;
  World() {
    ve::synth::SceneConfig config;
    config.seed = 4;
    std::vector<Eigen::Vector3d> path;
    for (int i = 0; i < kFrames; i += 5) path.push_back(cameraPose(i / kRate).translation());
    scene = ve::synth::Scene::makeRoom(config, path);
    renderer = std::make_unique<ve::synth::Renderer>(scene, camera);
  }
};

const World& world() {
  static const World w;
  return w;
}

struct TripRun {
  std::vector<ve::pipeline::FrameResult> results;
  ve::eval::Trajectory estimate, ground_truth;
};

// Frames [first, first + count) of the trip, rendered with noise seeds from seed_base.
TripRun runFrames(ve::pipeline::System* system, int first, int count, std::uint64_t seed_base) {
  TripRun run;
  for (int i = first; i < first + count; ++i) {
    const double t = kT0 + i / kRate;
    const Eigen::Isometry3d T_w_c = cameraPose(i / kRate);
    ve::synth::RenderOptions options;
    options.noise_sigma = 1.0;
    options.noise_seed = seed_base + static_cast<std::uint64_t>(i);
    run.results.push_back(system->process(world().renderer->render(T_w_c, options), t));
    run.ground_truth.push_back({t, T_w_c});
  }
  for (const auto& e : system->trajectory()) run.estimate.push_back({e.timestamp, e.T_w_c});
  return run;
}

class TempDir {
 public:
  TempDir() : path_(fs::temp_directory_path() / ("ve_map_persistence_" + std::to_string(::getpid()))) {
    fs::create_directories(path_);
  }
  ~TempDir() { fs::remove_all(path_); }
  std::string file(const std::string& name) const { return (path_ / name).string(); }

 private:
  fs::path path_;
};

std::string readAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

const TempDir& tempDir() {
  static const TempDir d;
  return d;
}

// The first run: maps the whole trip, saves the map, and gives its Sim(3) to ground truth.
struct FirstRun {
  std::string map_path = tempDir().file("wall.vemap");
  TripRun run;
  ve::eval::EvalResult eval;
  std::size_t keyframes = 0;  // indexed by the relocalizer
  FirstRun() {
    ve::pipeline::System system(ve::test::halfResolutionConfig(), world().camera);
    run = runFrames(&system, 0, kFrames, 4000);
    ve::eval::EvalConfig config;
    config.frames = kFrames;
    eval = ve::eval::evaluate(run.estimate, run.ground_truth, config);
    keyframes = system.exportMap().keyframe_index.size();
    std::string error;
    EXPECT_TRUE(system.saveMap(map_path, &error)) << error;
  }
};

const FirstRun& firstRun() {
  static const FirstRun r;
  return r;
}

// Position errors of a second run's poses mapped by the first run's Sim(3).
ve::eval::EvalResult withFirstRunAlignment(const TripRun& run) {
  ve::eval::EvalConfig config;
  config.given_alignment = firstRun().eval.alignment;
  return ve::eval::evaluate(run.estimate, run.ground_truth, config);
}

std::size_t mapPoints(const ve::map::MapFileContents& c) {
  std::size_t n = c.map.landmarks.size();
  for (const auto& d : c.map.dormant) n += d.revived ? 0 : 1;
  return n;
}

void expectAllLocalizedAfter(const TripRun& run, int first) {
  for (std::size_t i = static_cast<std::size_t>(first); i < run.results.size(); ++i) {
    EXPECT_TRUE(run.results[i].pose_valid) << "frame " << i << ": " << run.results[i].message;
  }
}

}  // namespace

TEST(SystemMapPersistence, FirstRunMapsTheTrip) {
  const FirstRun& r = firstRun();
  // Measured 0.136 cm, 77 keyframes: the map the later runs are scored against is that good.
  EXPECT_LT(r.eval.ate.rmse, 0.0021) << ve::eval::summary(r.eval, {});
  EXPECT_GT(r.keyframes, 10u);
  ASSERT_TRUE(fs::exists(r.map_path));
}

TEST(SystemMapPersistence, LocalizationOnlyFindsTheCameraInTheLoadedMapAndChangesNothing) {
  const FirstRun& first = firstRun();
  const std::string bytes_before = readAll(first.map_path);
  const ve::map::MapFileContents loaded = ve::map::loadMapFile(first.map_path);
  ve::pipeline::System system(ve::test::halfResolutionConfig(), world().camera);
  system.loadMap(loaded);
  system.setLocalizationOnly(true);
  EXPECT_TRUE(system.mapLoaded());
  const TripRun run = runFrames(&system, kSecondStart, kSecondFrames, 90000);

  // Found at once: measured, relocalized at the first frame against a keyframe
  // of the first run's way back over the same place (926 of 945 matches).
  EXPECT_EQ(run.results.front().state, TrackingState::kTracking) << run.results.front().message;
  EXPECT_EQ(run.results.front().reason, ve::pipeline::StateReason::kRelocalized) << run.results.front().message;
  expectAllLocalizedAfter(run, 10);
  EXPECT_EQ(system.initRetries(), 0);
  EXPECT_EQ(system.firstInitFrame(), -1);
  EXPECT_GE(system.relocalizations(), 1);
  EXPECT_EQ(run.results.front().frame_index, 0u);  // this stream's own numbering
  // In the first run's frame and scale: its Sim(3) to ground truth holds.
  // Measured 0.128 cm RMSE (the first run's own ATE: 0.136 cm); the bound is 1.5x that.
  const ve::eval::EvalResult e = withFirstRunAlignment(run);
  std::printf("[localization only] %zu of %d frames localized, ATE with the first run's Sim(3) %.4f cm\n", e.matched,
              kSecondFrames, 100.0 * e.ate.rmse);
  EXPECT_GE(e.matched, static_cast<std::size_t>(kSecondFrames - 10));
  EXPECT_LT(e.ate.rmse, 0.0019) << ve::eval::summary(e, {});
  // Nothing added: the same keyframes, no more points, the file untouched.
  const ve::map::MapFileContents after = system.exportMap();
  ASSERT_EQ(after.map.keyframes.size(), loaded.map.keyframes.size());
  for (std::size_t k = 0; k < after.map.keyframes.size(); ++k) {
    EXPECT_EQ(after.map.keyframes[k].frame_index, loaded.map.keyframes[k].frame_index);
    EXPECT_TRUE(after.map.keyframes[k].T_w_c.matrix() == loaded.map.keyframes[k].T_w_c.matrix());
  }
  EXPECT_EQ(after.keyframe_index.size(), loaded.keyframe_index.size());
  EXPECT_LE(mapPoints(after), mapPoints(loaded));
  EXPECT_TRUE(readAll(first.map_path) == bytes_before);
}

TEST(SystemMapPersistence, ExtendModeAddsKeyframesAndItsMapRoundTrips) {
  const FirstRun& first = firstRun();
  const ve::map::MapFileContents loaded = ve::map::loadMapFile(first.map_path);
  std::uint64_t last_loaded = 0;
  for (const auto& kf : loaded.keyframe_index) last_loaded = std::max(last_loaded, kf.frame_index);
  ve::pipeline::System system(ve::test::halfResolutionConfig(), world().camera);
  system.loadMap(loaded);
  const TripRun run = runFrames(&system, kSecondStart, kSecondFrames, 70000);
  expectAllLocalizedAfter(run, 10);
  EXPECT_EQ(system.initRetries(), 0);
  const ve::eval::EvalResult e = withFirstRunAlignment(run);
  // Measured 0.13 cm: extending does not degrade the loaded map's frame and scale.
  EXPECT_LT(e.ate.rmse, 0.002) << ve::eval::summary(e, {});

  // The new keyframes join the map after the loaded ones.
  const ve::map::MapFileContents extended = system.exportMap();
  std::size_t added = 0;
  for (const auto& kf : extended.keyframe_index) added += kf.frame_index > last_loaded ? 1 : 0;
  EXPECT_GT(added, 3u);
  EXPECT_GT(extended.map.keyframes.back().frame_index, last_loaded);

  // Save, load, save again: the same keyframes, points and poses, bit for bit.
  const std::string path1 = tempDir().file("extended.vemap");
  const std::string path2 = tempDir().file("extended_again.vemap");
  std::string error;
  ASSERT_TRUE(system.saveMap(path1, &error)) << error;
  ve::pipeline::System reloaded(ve::test::halfResolutionConfig(), world().camera);
  reloaded.loadMap(ve::map::loadMapFile(path1));
  ASSERT_TRUE(reloaded.saveMap(path2, &error)) << error;
  const std::string a = readAll(path1), b = readAll(path2);
  EXPECT_GT(a.size(), 1000u);
  EXPECT_TRUE(a == b) << "sizes " << a.size() << " and " << b.size();
}

// Extend mode: found in the loaded map, then the camera turned at once to the
// room's other side, which the first run never saw, for more frames than
// relocalization.max_frames. No new map (it would discard the loaded one, and a
// later save would overwrite its file); back on the trip, found again.
namespace {
void expectALossIsNeverGivenUp(const ve::pipeline::SystemConfig& config) {
  const ve::map::MapFileContents loaded = ve::map::loadMapFile(firstRun().map_path);
  ve::pipeline::System system(config, world().camera);
  system.loadMap(loaded);
  const TripRun start = runFrames(&system, kSecondStart, 20, 50000);
  expectAllLocalizedAfter(start, 0);
  const int away = config.relocalization.max_frames + 10;
  int lost = 0;
  for (int i = 0; i < away; ++i) {
    const int k = kSecondStart + 20 + i;
    Eigen::Isometry3d T_w_c = cameraPose(k / kRate);
    T_w_c.linear() = Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitZ()).toRotationMatrix() * T_w_c.linear();
    ve::synth::RenderOptions options;
    options.noise_sigma = 1.0;
    options.noise_seed = 50000 + static_cast<std::uint64_t>(k);
    const ve::pipeline::FrameResult r = system.process(world().renderer->render(T_w_c, options), kT0 + k / kRate);
    lost += r.pose_valid ? 0 : 1;
    if (i == 0) {
      EXPECT_FALSE(r.pose_valid) << "the cut was tracked: " << r.message;
    }
  }
  EXPECT_GE(lost, away - 2) << "the turned camera was not lost";
  EXPECT_EQ(system.initRetries(), 0);
  const TripRun back = runFrames(&system, kSecondStart + 20 + away, 40, 60000);
  expectAllLocalizedAfter(back, 10);
  EXPECT_EQ(system.initRetries(), 0);
  EXPECT_EQ(system.firstInitFrame(), -1);
  EXPECT_GE(system.relocalizations(), 2);
}
}  // namespace

TEST(SystemMapPersistence, WithALoadedMapALossIsNeverGivenUpForANewMap) {
  expectALossIsNeverGivenUp(ve::test::halfResolutionConfig());
}

TEST(SystemMapPersistence, TheShippedTrackerSettingsLoseTheCameraAtACut) {
  // Without the patch confirmation (every shipped config) about 13 % of the map
  // tracks survive the cut on nearby extrema, and a third of them agree on a pose
  // near the motion model's prediction; a cut is told by that collapse of the
  // survival against the frames before it (TrackSurvival), not by the pose.
  ve::pipeline::SystemConfig config = ve::test::halfResolutionConfig();
  config.tracker.lambda = 2.0;
  config.tracker.strength_at_subpixel_peak = false;
  config.tracker.max_align_disagreement_px = 0.0;
  config.tracker.extremum_weight = 0.5;
  config.tracker.align_radius_px = 3;
  expectALossIsNeverGivenUp(config);
}

TEST(SystemMapPersistence, PipelinedSystemLocalizesInALoadedMap) {
  // The two-thread system (vitamin_e_run --pipelined, the ROS nodelet's mode of
  // work) given the map before its first frame: found at once, every frame
  // localized after the first few, in the first run's frame and scale, the map unchanged.
  const ve::map::MapFileContents loaded = ve::map::loadMapFile(firstRun().map_path);
  std::vector<ve::pipeline::FrameResult> results;  // written on the mapping thread, read after flush()
  ve::pipeline::PipelinedSystem pipelined(ve::test::halfResolutionConfig(), world().camera, {},
                                          [&](ve::pipeline::FrameResult r) { results.push_back(std::move(r)); });
  pipelined.system().loadMap(loaded);
  pipelined.system().setLocalizationOnly(true);
  TripRun run;
  for (int i = kSecondStart; i < kSecondStart + kSecondFrames; ++i) {
    const double t = kT0 + i / kRate;
    const Eigen::Isometry3d T_w_c = cameraPose(i / kRate);
    ve::synth::RenderOptions options;
    options.noise_sigma = 1.0;
    options.noise_seed = 90000 + static_cast<std::uint64_t>(i);
    ASSERT_TRUE(pipelined.submit(world().renderer->render(T_w_c, options), t));
    run.ground_truth.push_back({t, T_w_c});
  }
  pipelined.flush();
  const ve::pipeline::System& system = pipelined.system();
  for (const auto& e : system.trajectory()) run.estimate.push_back({e.timestamp, e.T_w_c});
  run.results = results;
  ASSERT_EQ(run.results.size(), static_cast<std::size_t>(kSecondFrames));
  EXPECT_EQ(run.results.front().reason, ve::pipeline::StateReason::kRelocalized) << run.results.front().message;
  expectAllLocalizedAfter(run, 10);
  EXPECT_EQ(system.initRetries(), 0);
  EXPECT_EQ(system.firstInitFrame(), -1);
  const ve::eval::EvalResult e = withFirstRunAlignment(run);
  std::printf("[pipelined, loaded map] %zu of %d frames localized, ATE with the first run's Sim(3) %.4f cm\n",
              e.matched, kSecondFrames, 100.0 * e.ate.rmse);
  EXPECT_GE(e.matched, static_cast<std::size_t>(kSecondFrames - 10));
  // Measured 0.128 cm, as the sequential system's: the bound is 1.5x that.
  EXPECT_LT(e.ate.rmse, 0.0019) << ve::eval::summary(e, {});
  const ve::map::MapFileContents after = system.exportMap();
  EXPECT_EQ(after.map.keyframes.size(), loaded.map.keyframes.size());
  EXPECT_EQ(after.keyframe_index.size(), loaded.keyframe_index.size());
}

TEST(SystemMapPersistence, AMapFromAnotherCameraSizeIsRefusedByName) {
  const ve::map::MapFileContents loaded = ve::map::loadMapFile(firstRun().map_path);
  ve::pipeline::System system(ve::test::halfResolutionConfig(), ve::synth::makeSequenceCamera(752, 480, true));
  try {
    system.loadMap(loaded);
    ADD_FAILURE() << "a 376x240 map was loaded into a 752x480 system";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("376x240"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("752x480"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(system.mapLoaded());
  // Nor after the first frame.
  ve::pipeline::System late(ve::test::halfResolutionConfig(), world().camera);
  runFrames(&late, 0, 1, 1);
  EXPECT_THROW(late.loadMap(loaded), std::invalid_argument);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
