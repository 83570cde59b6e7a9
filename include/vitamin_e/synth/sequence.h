#pragma once
// Writes a synthetic monocular sequence in the EuRoC ASL layout (the same names
// as the shared renderer, so the same tools read both). Two scenes: "room" (the
// textured room with boxes, figure-eight path, EuRoC camera) and "street" (the
// town of street.h driven along a named drive path, KITTI camera):
//   OUT/mav0/cam0/data/<t_ns>.png, OUT/mav0/cam0/data.csv ("#timestamp [ns],filename"),
//   OUT/mav0/cam0/sensor.yaml (EuRoC format, T_BS = identity: body = camera),
//   OUT/mav0/state_groundtruth_estimate0/data.csv (camera = body pose, image rate),
//   OUT/groundtruth_cam0_tum.txt (T_w_c at each image, TUM, seconds),
//   OUT/scene.json (room, boxes, faces, camera, path, settings).
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "vitamin_e/camera/camera.h"
#include "vitamin_e/synth/camera_path.h"
#include "vitamin_e/synth/drive_path.h"
#include "vitamin_e/synth/scene.h"

namespace vitamin_e::synth {

struct SequenceConfig {
  std::string scene = "room";  // "room" or "street" (start from defaultSequenceConfig(scene))
  std::string path = "drive";  // street: the drive path (makeDrivePathConfig)
  int frames = 400;            // street: 0 = the whole path
  double rate_hz = 20.0;
  int width = 752;
  int height = 480;
  std::uint64_t seed = 0;
  double speed = 0.4;        // mean camera speed [m/s]
  double noise_sigma = 1.0;  // Gaussian image noise [grey levels]
  bool distortion = true;    // EuRoC cam0 radial-tangential; false: pinhole
  int supersample = 1;       // s x s rays per pixel (mip filtering is always on)
  double texel_m = 0.005;
  int num_boxes = 6;  // room only
  std::int64_t start_ns = 1600000000000000000LL;
  void validate() const;  // throws std::invalid_argument naming the key
};

// The defaults of a scene: "room" as SequenceConfig{}; "street": the KITTI
// camera (1226x370, no distortion, 10 Hz), the whole "drive" path, texel 2 cm.
// Throws std::invalid_argument for another scene name.
SequenceConfig defaultSequenceConfig(const std::string& scene);

// EuRoC cam0 intrinsics (fu fv cu cv = 458.654 457.296 367.215 248.375 at
// 752x480) scaled to width x height, with its radial-tangential distortion or none.
camera::Camera makeSequenceCamera(int width, int height, bool distortion);
// KITTI odometry's grey camera (fx = fy = 707.0912, cx = 601.8873, cy = 183.1104
// at 1226x370, rectified: no distortion) scaled to width x height.
camera::Camera makeKittiCamera(int width, int height);
// The camera of a sequence: makeSequenceCamera (room) or makeKittiCamera (street).
camera::Camera sequenceCamera(const SequenceConfig& config);
// The street sequence's town around its path, textures matched to the camera
// (the texel grows with distance like the camera's pixel footprint).
Scene makeStreetSequenceScene(const SequenceConfig& config, const DrivePath& path, const camera::Camera& camera);
// Frames of a street sequence: config.frames, or the whole path if 0. Throws
// std::invalid_argument if config.frames exceeds the path.
int streetSequenceFrames(const SequenceConfig& config, const DrivePath& path);
// The camera path of a (room) sequence (speed from the config, heading from the seed).
CameraPathConfig makeSequencePath(const SequenceConfig& config);
// The scene of a sequence: boxes kept clear of the whole path.
Scene makeSequenceScene(const SequenceConfig& config, const CameraPath& path);
// Timestamp of frame i [ns].
std::int64_t frameTimestampNs(const SequenceConfig& config, int i);

struct SequenceStats {
  int frames = 0;
  double scene_build_s = 0.0;
  double render_ms_mean = 0.0;  // rendering only, per frame
  double write_ms_mean = 0.0;   // PNG encoding + writing, per frame
};

// Renders and writes the sequence into out_dir (created; existing files are
// overwritten). progress(done, total) is called after every frame. Throws
// std::runtime_error naming the file on I/O failure.
SequenceStats writeSequence(const std::string& out_dir, const SequenceConfig& config,
                            const std::function<void(int, int)>& progress = {});

// EuRoC sensor.yaml text for a camera (T_BS = identity).
std::string eurocSensorYaml(const camera::Camera& camera, double rate_hz);

}  // namespace vitamin_e::synth
