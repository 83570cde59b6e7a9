// Map file benchmark: time to load a map (read, check and parse the file, then
// System::loadMap: the map restored and the relocalizer's index rebuilt), and
// the save -> load -> save round trip of a real map.
//   bench_system_map_file [--points N] [--keyframes K] [--repeat R]   synthetic map
//   bench_system_map_file --map FILE [--config YAML] [--repeat R]     a saved map
// The synthetic map has N points (a window of 10 keyframes with 2,000 landmarks,
// the rest dormant), N archived points and K indexed keyframes of 1,500
// described points each (the relocalizer's defaults: the largest index it keeps).
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <string>
#include <vector>

#include "cli.h"
#include "vitamin_e/common/timing.h"
#include "vitamin_e/map/map_file.h"
#include "vitamin_e/pipeline/relocalizer.h"
#include "vitamin_e/pipeline/system.h"

namespace ve = vitamin_e;
namespace fs = std::filesystem;

namespace {

namespace cli = vitamin_e::cli;
using cli::fail;

const char* const kUsage =
    "usage: bench_system_map_file [--points N] [--keyframes K] [--repeat R] | --map FILE [--config YAML] [--repeat R]\n"
    "  --points N     synthetic map: N points (landmarks and dormant), N archived (default 100000)\n"
    "  --keyframes K  synthetic map: K indexed keyframes of 1,500 points (default 400, the relocalizer's maximum)\n"
    "  --map FILE     a saved map instead: its load time and the load -> save round trip (same bytes)\n"
    "  --config YAML  the configuration the map was made with (the keyframe window, the descriptors)\n"
    "  --repeat R     loads timed (default 5)\n";

std::string readAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

ve::map::MapFileContents syntheticMap(std::size_t points, std::size_t indexed_keyframes) {
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> u(-5.0, 5.0), n(-0.5, 0.5);
  ve::map::MapFileContents c;
  c.camera =
      ve::camera::Camera(752, 480, 458.654, 457.296, 367.215, 248.375, ve::camera::DistortionModel::kRadialTangential,
                         {-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05});
  c.scale_convention = "synthetic";
  c.scene_depth = 1.0;
  const ve::pipeline::RelocalizerConfig reloc;
  c.descriptors = {reloc.patch_size, reloc.smoothing_sigma};
  const std::size_t window = 10, active = std::min<std::size_t>(points, 2000);
  std::uint64_t id = 1;
  for (std::size_t k = 0; k < window; ++k) {
    ve::map::Keyframe kf;
    kf.frame_index = 10000 + 10 * k;
    kf.timestamp = 100.0 + static_cast<double>(k);
    kf.T_w_c.translation() = Eigen::Vector3d(0.1 * static_cast<double>(k), 0.0, 0.0);
    for (std::size_t i = 0; i < active; ++i) kf.observations.emplace(i + 1, Eigen::Vector2d(n(rng), n(rng)));
    c.map.keyframes.push_back(kf);
  }
  for (std::size_t i = 0; i < active; ++i) {
    ve::map::Landmark l;
    l.id = id++;
    l.p_w = Eigen::Vector3d(u(rng), u(rng), u(rng));
    l.polarity = i % 2 ? 1 : -1;
    l.num_observations = static_cast<int>(window);
    l.last_seen_frame = 10090;
    c.map.landmarks.push_back(l);
  }
  for (std::size_t i = active; i < points; ++i) {
    ve::map::DormantLandmark d;
    d.id = id++;
    d.p_w = Eigen::Vector3d(u(rng), u(rng), u(rng));
    d.polarity = i % 2 ? 1 : -1;
    d.num_observations = 4;
    c.map.dormant.push_back(d);
  }
  for (std::size_t i = 0; i < points; ++i) c.map.archive.push_back({Eigen::Vector3d(u(rng), u(rng), u(rng)), 128});
  for (std::size_t k = 0; k < indexed_keyframes; ++k) {
    ve::map::IndexedKeyframe kf;
    kf.frame_index = 10 * k;
    kf.T_w_c.translation() = Eigen::Vector3d(0.01 * static_cast<double>(k), 0.0, 0.0);
    kf.points.resize(static_cast<std::size_t>(reloc.points_per_keyframe));
    for (ve::map::IndexedPoint& p : kf.points) {
      p.landmark_id = 1 + rng() % (id - 1);
      p.p_w = Eigen::Vector3d(u(rng), u(rng), u(rng));
      for (auto& b : p.descriptor) b = rng();
      p.polarity = rng() % 2 ? 1 : -1;
    }
    c.keyframe_index.push_back(kf);
  }
  return c;
}

struct LoadTimes {
  std::vector<double> file_ms, system_ms;
};

// Loads `path` `repeat` times into fresh systems.
LoadTimes timeLoads(const std::string& path, const ve::pipeline::SystemConfig& config, int repeat) {
  LoadTimes t;
  for (int r = 0; r < repeat; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    const ve::map::MapFileContents c = ve::map::loadMapFile(path);
    t.file_ms.push_back(ve::elapsedMs(t0));
    ve::pipeline::System system(config, c.camera);
    const auto t1 = std::chrono::steady_clock::now();
    system.loadMap(c);
    t.system_ms.push_back(ve::elapsedMs(t1));
  }
  return t;
}

void report(const std::string& what, const LoadTimes& t) {
  std::vector<double> total(t.file_ms.size());
  for (std::size_t i = 0; i < total.size(); ++i) total[i] = t.file_ms[i] + t.system_ms[i];
  std::printf("%s: load median %.0f ms (file %.0f ms + System::loadMap %.0f ms), max %.0f ms over %zu loads\n",
              what.c_str(), ve::upperMedian(total), ve::upperMedian(t.file_ms), ve::upperMedian(t.system_ms),
              *std::max_element(total.begin(), total.end()), total.size());
}

}  // namespace

int main(int argc, char** argv) {
  std::size_t points = 100000, keyframes = 400;
  int repeat = 5;
  std::string map_path, config_path;
  cli::ArgParser args(argc, argv, kUsage);
  while (args.more()) {
    if (args.value("--points", &points) || args.value("--keyframes", &keyframes) || args.value("--repeat", &repeat) ||
        args.value("--map", &map_path) || args.value("--config", &config_path)) {
      continue;
    }
    args.unknown();
  }
  if (repeat < 1) fail("--repeat must be >= 1");
  try {
    const ve::pipeline::SystemConfig config =
        config_path.empty() ? ve::pipeline::SystemConfig{} : ve::pipeline::loadSystemConfig(config_path);
    const fs::path dir = fs::temp_directory_path() / ("ve_bench_map_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    if (map_path.empty()) {
      map_path = (dir / "synthetic.vemap").string();
      const ve::map::MapFileContents c = syntheticMap(points, keyframes);
      const auto t0 = std::chrono::steady_clock::now();
      std::string error;
      if (!ve::map::saveMapFile(c, map_path, &error)) fail(error);
      std::printf("%s: %.1f MB, written in %.0f ms\n", ve::map::mapFileHeader(c).c_str(),
                  static_cast<double>(fs::file_size(map_path)) / 1e6, ve::elapsedMs(t0));
      report("synthetic map", timeLoads(map_path, config, repeat));
      // Where System::loadMap's time goes.
      const auto t1 = std::chrono::steady_clock::now();
      ve::map::Map map(config.map);
      map.restore(c.map);
      const double restore_ms = ve::elapsedMs(t1);
      ve::geometry::PnpConfig pnp;
      ve::pipeline::Relocalizer relocalizer(config.relocalization, c.camera, pnp);
      const auto t2 = std::chrono::steady_clock::now();
      relocalizer.importEntries(c.keyframe_index);
      std::printf("  Map::restore %.0f ms, Relocalizer::importEntries %.0f ms (%zu keyframes)\n", restore_ms,
                  ve::elapsedMs(t2), relocalizer.size());
    } else {
      const ve::map::MapFileContents c = ve::map::loadMapFile(map_path);
      std::printf("%s: %s, %.1f MB\n", map_path.c_str(), ve::map::mapFileHeader(c).c_str(),
                  static_cast<double>(fs::file_size(map_path)) / 1e6);
      report(map_path, timeLoads(map_path, config, repeat));
      // Round trip: loaded into a system and saved again, the same bytes.
      ve::pipeline::System system(config, c.camera);
      system.loadMap(c);
      const std::string again = (dir / "again.vemap").string();
      std::string error;
      if (!system.saveMap(again, &error)) fail(error);
      const bool same = readAll(again) == readAll(map_path);
      std::printf("round trip (load, save): %s\n", same ? "identical bytes" : "DIFFERENT bytes");
      if (!same) return 1;
    }
    fs::remove_all(dir);
  } catch (const std::exception& e) {
    fail(e.what());
  }
  return 0;
}
