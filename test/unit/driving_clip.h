#pragma once
// Short driving clips for the system tests: the project's street scene
// (src/synth/street.cpp) driven along a named path (drive_path.h), rendered in
// memory with KITTI's camera, by default scaled to 613x185 (half of 1226x370:
// a clip renders and runs in seconds), and the SLAM system run over it with
// config/kitti.yaml adapted to that size. Deterministic: fixed scene seed and
// per-frame noise seeds.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "vitamin_e/eval/metrics.h"
#include "vitamin_e/pipeline/system.h"
#include "vitamin_e/synth/drive_path.h"
#include "vitamin_e/synth/renderer.h"
#include "vitamin_e/synth/sequence.h"

namespace vitamin_e::test {

struct DrivingClip {
  std::string path_name;
  camera::Camera camera;
  double rate_hz = 10.0;
  std::vector<cv::Mat> images;
  eval::Trajectory ground_truth;  // T_w_c of every image
  double path_length_m = 0.0;     // driven over the clip
};

// Which part of which path, at which size.
struct ClipSpec {
  std::string path = "turn";  // a drive path name (synth::drivePathNames)
  int width = 613;            // KITTI's camera scaled to width x height
  int height = 185;
  int first = 0;           // first frame of the path (10 Hz)
  int frames = 0;          // 0: to the end of the path
  std::uint64_t seed = 0;  // town and noise
  double t0 = 100.0;       // timestamp of the clip's first image [s]
};

// The frames of a clip, with sensor noise sigma 1 grey level (seeded per frame
// of the path, so a sub-clip has the same images as the whole path).
inline DrivingClip renderDrivingClip(const ClipSpec& spec) {
  synth::SequenceConfig seq = synth::defaultSequenceConfig("street");
  seq.path = spec.path;
  seq.width = spec.width;
  seq.height = spec.height;
  seq.seed = spec.seed;
  const synth::DrivePath path(synth::makeDrivePathConfig(spec.path));
  DrivingClip clip;
  clip.path_name = spec.path;
  clip.camera = synth::sequenceCamera(seq);
  clip.rate_hz = seq.rate_hz;
  const int whole = synth::streetSequenceFrames(seq, path);
  const int end = spec.frames > 0 ? std::min(whole, spec.first + spec.frames) : whole;
  const synth::Scene scene = synth::makeStreetSequenceScene(seq, path, clip.camera);
  const synth::Renderer renderer(scene, clip.camera);
  for (int i = spec.first; i < end; ++i) {
    const double t = i / seq.rate_hz;
    synth::RenderOptions options;
    options.noise_sigma = 1.0;
    options.noise_seed = synth::mixSeed(spec.seed, 0xD81E, static_cast<std::uint64_t>(i));
    clip.images.push_back(renderer.render(path.T_w_c(t), options));
    clip.ground_truth.push_back({spec.t0 + (i - spec.first) / seq.rate_hz, path.T_w_c(t)});
  }
  if (!clip.images.empty())
    clip.path_length_m = path.arcLength((end - 1) / seq.rate_hz) - path.arcLength(spec.first / seq.rate_hz);
  return clip;
}

// config/kitti.yaml (tuned at 1226x370) with its pixel-sized settings scaled to
// an image `scale` times as wide: point budget and grid cells, the dominant-flow
// image (the same small image size), and the pipeline's pixel thresholds. The counts of
// points (tracks to initialize, road points) follow the point budget by themselves.
inline pipeline::SystemConfig drivingConfig(double scale = 0.5) {
  pipeline::SystemConfig c = pipeline::loadSystemConfig(std::string(VITAMIN_E_SOURCE_DIR) + "/config/kitti.yaml");
  c.tracker.max_points = static_cast<int>(std::lround(c.tracker.max_points * scale * scale));
  c.tracker.grid_cell_px = std::max(2, static_cast<int>(std::lround(c.tracker.grid_cell_px * scale)));
  c.tracker.brief_scale = std::min(1.0, c.tracker.brief_scale / scale);
  c.init_min_disparity_px *= scale;
  c.keyframe_parallax_px *= scale;
  return c;
}

struct DrivingRun {
  std::vector<pipeline::FrameResult> results;
  eval::Trajectory estimate;
  int init_retries = 0;
  long long first_init_frame = -1;
  std::size_t frames_tracked_since_init = 0;
  double seconds = 0.0;  // wall time of the SLAM (not the rendering)
};

inline DrivingRun runDrivingClip(const DrivingClip& clip, const pipeline::SystemConfig& config) {
  pipeline::System system(config, clip.camera);
  DrivingRun run;
  const auto start = std::chrono::steady_clock::now();
  for (std::size_t i = 0; i < clip.images.size(); ++i)
    run.results.push_back(system.process(clip.images[i], clip.ground_truth[i].t));
  run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  for (const auto& e : system.trajectory()) run.estimate.push_back({e.timestamp, e.T_w_c});
  run.init_retries = system.initRetries();
  run.first_init_frame = system.firstInitFrame();
  run.frames_tracked_since_init = system.framesTrackedSinceInit();
  return run;
}

}  // namespace vitamin_e::test
