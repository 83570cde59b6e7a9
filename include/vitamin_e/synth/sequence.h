#pragma once
// Writes a synthetic monocular sequence in the EuRoC ASL layout (the same names
// as the shared renderer, so the same tools read both):
//   OUT/mav0/cam0/data/<t_ns>.png, OUT/mav0/cam0/data.csv ("#timestamp [ns],filename"),
//   OUT/mav0/cam0/sensor.yaml (EuRoC format, T_BS = identity: body = camera),
//   OUT/mav0/state_groundtruth_estimate0/data.csv (camera = body pose, image rate),
//   OUT/groundtruth_cam0_tum.txt (T_w_c at each image, TUM, seconds),
//   OUT/scene.json (room, boxes, faces, camera, path, settings).
#include <cstdint>
#include <functional>
#include <string>

#include "vitamin_e/camera/camera.h"
#include "vitamin_e/synth/camera_path.h"
#include "vitamin_e/synth/scene.h"

namespace vitamin_e::synth {

struct SequenceConfig {
  int frames = 400;
  double rate_hz = 20.0;
  int width = 752;
  int height = 480;
  std::uint64_t seed = 0;
  double speed = 0.4;          // mean camera speed [m/s]
  double noise_sigma = 1.0;    // Gaussian image noise [grey levels]
  bool distortion = true;      // EuRoC cam0 radial-tangential; false: pinhole
  int supersample = 1;         // s x s rays per pixel (mip filtering is always on)
  double texel_m = 0.005;
  int num_boxes = 6;
  std::int64_t start_ns = 1600000000000000000LL;
  void validate() const;       // throws std::invalid_argument naming the key
};

// EuRoC cam0 intrinsics (fu fv cu cv = 458.654 457.296 367.215 248.375 at
// 752x480) scaled to width x height, with its radial-tangential distortion or none.
camera::Camera makeSequenceCamera(int width, int height, bool distortion);
// The camera path of a sequence (speed from the config, heading from the seed).
CameraPathConfig makeSequencePath(const SequenceConfig& config);
// The scene of a sequence: boxes kept clear of the whole path.
Scene makeSequenceScene(const SequenceConfig& config, const CameraPath& path);
// Timestamp of frame i [ns].
std::int64_t frameTimestampNs(const SequenceConfig& config, int i);

struct SequenceStats {
  int frames = 0;
  double scene_build_s = 0.0;
  double render_ms_mean = 0.0;   // rendering only, per frame
  double write_ms_mean = 0.0;    // PNG encoding + writing, per frame
};

// Renders and writes the sequence into out_dir (created; existing files are
// overwritten). progress(done, total) is called after every frame. Throws
// std::runtime_error naming the file on I/O failure.
SequenceStats writeSequence(const std::string& out_dir, const SequenceConfig& config,
                            const std::function<void(int, int)>& progress = {});

// EuRoC sensor.yaml text for a camera (T_BS = identity).
std::string eurocSensorYaml(const camera::Camera& camera, double rate_hz);

}  // namespace vitamin_e::synth
