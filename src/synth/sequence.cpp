#include "vitamin_e/synth/sequence.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <stdexcept>

#include <opencv2/imgcodecs.hpp>

#include "vitamin_e/common/timing.h"
#include "vitamin_e/synth/renderer.h"
#include "vitamin_e/synth/street.h"

namespace vitamin_e::synth {
namespace fs = std::filesystem;

void SequenceConfig::validate() const {
  if (scene != "room" && scene != "street")
    throw std::invalid_argument("scene must be room or street, got '" + scene + "'");
  if (scene == "street") {
    if (frames < 0) throw std::invalid_argument("frames must be >= 0 (0: the whole path)");
    if (!(rate_hz > 0.0 && rate_hz <= 1000.0)) throw std::invalid_argument("rate_hz must be in (0, 1000]");
    streetSequenceFrames(*this, DrivePath(makeDrivePathConfig(path)));  // unknown path, too many frames
    if (distortion) throw std::invalid_argument("distortion: the street scene's (KITTI) camera has none");
  } else if (frames < 1) {
    throw std::invalid_argument("frames must be >= 1");
  }
  if (!(rate_hz > 0.0 && rate_hz <= 1000.0)) throw std::invalid_argument("rate_hz must be in (0, 1000]");
  if (width < 16 || height < 16 || width > 8192 || height > 8192)
    throw std::invalid_argument("width/height must be in [16, 8192]");
  if (!(speed > 0.0 && speed < 20.0)) throw std::invalid_argument("speed must be in (0, 20) m/s");
  if (!(noise_sigma >= 0.0 && noise_sigma <= 50.0)) throw std::invalid_argument("noise_sigma must be in [0, 50]");
  if (supersample < 1 || supersample > 4) throw std::invalid_argument("supersample must be in [1, 4]");
  if (!(texel_m >= 0.001 && texel_m <= 0.1)) throw std::invalid_argument("texel_m must be in [0.001, 0.1]");
  if (num_boxes < 0 || num_boxes > 64) throw std::invalid_argument("num_boxes must be in [0, 64]");
  if (start_ns < 0) throw std::invalid_argument("start_ns must be >= 0");
}

camera::Camera makeSequenceCamera(int width, int height, bool distortion) {
  const double sx = width / 752.0, sy = height / 480.0;
  std::vector<double> d;
  auto model = camera::DistortionModel::kNone;
  if (distortion) {
    model = camera::DistortionModel::kRadialTangential;
    d = {-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05};
  }
  return camera::Camera(width, height, 458.654 * sx, 457.296 * sy, (367.215 + 0.5) * sx - 0.5,
                        (248.375 + 0.5) * sy - 0.5, model, d);
}

SequenceConfig defaultSequenceConfig(const std::string& scene) {
  SequenceConfig c;
  if (scene == "room") return c;
  if (scene != "street") throw std::invalid_argument("scene must be room or street, got '" + scene + "'");
  c.scene = "street";
  c.path = "drive";
  c.frames = 0;
  c.rate_hz = 10.0;
  c.width = 1226;
  c.height = 370;
  c.distortion = false;
  c.texel_m = 0.02;
  return c;
}

camera::Camera makeKittiCamera(int width, int height) {
  const double sx = width / 1226.0, sy = height / 370.0;
  return camera::Camera(width, height, 707.0912 * sx, 707.0912 * sy, (601.8873 + 0.5) * sx - 0.5,
                        (183.1104 + 0.5) * sy - 0.5);
}

camera::Camera sequenceCamera(const SequenceConfig& config) {
  return config.scene == "street" ? makeKittiCamera(config.width, config.height)
                                  : makeSequenceCamera(config.width, config.height, config.distortion);
}

Scene makeStreetSequenceScene(const SequenceConfig& config, const DrivePath& path, const camera::Camera& camera) {
  StreetConfig sc;
  sc.seed = config.seed;
  sc.texel_m = config.texel_m;
  // About 0.85 texel per pixel on a surface facing the camera at the face's nearest.
  sc.texel_per_m = 0.85 / camera.fx();
  sc.max_texel_m = std::max(sc.texel_m, 0.2);
  return makeStreetScene(sc, path);
}

int streetSequenceFrames(const SequenceConfig& config, const DrivePath& path) {
  const int whole = static_cast<int>(std::floor(path.duration() * config.rate_hz + 1e-9)) + 1;
  if (config.frames > whole)
    throw std::invalid_argument("frames: path '" + config.path + "' lasts " + std::to_string(path.duration()) +
                                " s: at most " + std::to_string(whole) + " frames at " +
                                std::to_string(config.rate_hz) + " Hz");
  return config.frames > 0 ? config.frames : whole;
}

CameraPathConfig makeSequencePath(const SequenceConfig& config) {
  CameraPathConfig p;
  p.speed = config.speed;
  Rng rng(mixSeed(config.seed, 0x9A7B));
  p.heading0 = rng.uniform(-M_PI, M_PI);
  return p;
}

Scene makeSequenceScene(const SequenceConfig& config, const CameraPath& path) {
  SceneConfig sc;
  sc.seed = config.seed;
  sc.texel_m = config.texel_m;
  sc.num_boxes = config.num_boxes;
  const double duration = config.frames / config.rate_hz;
  // The figure-eight repeats: one period covers every place the camera goes.
  const double period = 2.0 * M_PI / path.angularRate();
  return Scene::makeRoom(sc, path.samplePositions(std::min(duration, period), 0.05));
}

std::int64_t frameTimestampNs(const SequenceConfig& config, int i) {
  return config.start_ns + static_cast<std::int64_t>(std::llround(i * 1e9 / config.rate_hz));
}

std::string eurocSensorYaml(const camera::Camera& cam, double rate_hz) {
  std::ostringstream o;
  o.precision(12);
  o << "%YAML:1.0\n# vitamin_e synthetic camera (vitamin_e_make_sequence)\nsensor_type: camera\n"
    << "comment: vitamin_e synthetic cam0\n\n# Sensor extrinsics wrt. the body-frame (body = camera).\nT_BS:\n"
    << "  cols: 4\n  rows: 4\n  data: [1.0, 0.0, 0.0, 0.0,\n         0.0, 1.0, 0.0, 0.0,\n"
    << "         0.0, 0.0, 1.0, 0.0,\n         0.0, 0.0, 0.0, 1.0]\n\n# Camera specific definitions.\n"
    << "rate_hz: " << rate_hz << "\nresolution: [" << cam.width() << ", " << cam.height() << "]\n"
    << "camera_model: pinhole\nintrinsics: [" << cam.fx() << ", " << cam.fy() << ", " << cam.cx() << ", " << cam.cy()
    << "] #fu, fv, cu, cv\ndistortion_model: radial-tangential\ndistortion_coefficients: [";
  std::vector<double> d = cam.distortion();
  if (d.empty()) d = {0.0, 0.0, 0.0, 0.0};
  for (std::size_t i = 0; i < d.size(); ++i) o << (i ? ", " : "") << d[i];
  o << "]\n";
  return o.str();
}

namespace {

std::string secondsText(std::int64_t ns) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%lld.%09lld", static_cast<long long>(ns / 1000000000LL),
                static_cast<long long>(ns % 1000000000LL));
  return buf;
}

std::ofstream openOut(const fs::path& p) {
  std::ofstream f(p);
  if (!f) throw std::runtime_error(p.string() + ": cannot write");
  return f;
}

}  // namespace

SequenceStats writeSequence(const std::string& out_dir, const SequenceConfig& config,
                            const std::function<void(int, int)>& progress) {
  config.validate();
  SequenceStats stats;
  const fs::path out(out_dir), cam_dir = out / "mav0" / "cam0", img_dir = cam_dir / "data",
                               gt_dir = out / "mav0" / "state_groundtruth_estimate0";
  std::error_code ec;
  fs::create_directories(img_dir, ec);
  fs::create_directories(gt_dir, ec);
  if (!fs::is_directory(img_dir)) throw std::runtime_error(img_dir.string() + ": cannot create folder");

  const auto t_scene = TimingClock::now();
  const camera::Camera cam = sequenceCamera(config);
  const bool street = config.scene == "street";
  // One of the two: the room's figure-eight or the street's drive.
  std::unique_ptr<CameraPath> room_path;
  std::unique_ptr<DrivePath> drive_path;
  std::unique_ptr<Scene> scene_ptr;
  int frames = config.frames;
  if (street) {
    drive_path = std::make_unique<DrivePath>(makeDrivePathConfig(config.path));
    frames = streetSequenceFrames(config, *drive_path);
    scene_ptr = std::make_unique<Scene>(makeStreetSequenceScene(config, *drive_path, cam));
  } else {
    room_path = std::make_unique<CameraPath>(makeSequencePath(config));
    scene_ptr = std::make_unique<Scene>(makeSequenceScene(config, *room_path));
  }
  const Scene& scene = *scene_ptr;
  auto pose = [&](double t) { return street ? drive_path->T_w_c(t) : room_path->T_w_c(t); };
  const Renderer renderer(scene, cam, config.supersample);
  stats.scene_build_s = elapsedMs(t_scene) / 1000.0;

  openOut(cam_dir / "sensor.yaml") << eurocSensorYaml(cam, config.rate_hz);
  auto csv = openOut(cam_dir / "data.csv");
  csv << "#timestamp [ns],filename\n";
  auto tum = openOut(out / "groundtruth_cam0_tum.txt");
  tum << "# camera (cam0) poses T_W_C at image timestamps: timestamp[s] tx ty tz qx qy qz qw\n";
  auto body = openOut(gt_dir / "data.csv");
  body << "#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], q_RS_z []\n";

  double render_ms = 0.0, write_ms = 0.0;
  char line[256];
  for (int i = 0; i < frames; ++i) {
    const std::int64_t ns = frameTimestampNs(config, i);
    const Eigen::Isometry3d T_w_c = pose(i / config.rate_hz);
    RenderOptions ro;
    ro.noise_sigma = config.noise_sigma;
    ro.noise_seed = mixSeed(config.seed, 0x401CE, static_cast<std::uint64_t>(i));
    const auto t0 = TimingClock::now();
    const cv::Mat img = renderer.render(T_w_c, ro);
    render_ms += elapsedMs(t0);
    const auto t1 = TimingClock::now();
    const std::string name = std::to_string(ns) + ".png";
    if (!cv::imwrite((img_dir / name).string(), img))
      throw std::runtime_error((img_dir / name).string() + ": cannot write");
    write_ms += elapsedMs(t1);

    csv << ns << "," << name << "\n";
    Eigen::Quaterniond q(T_w_c.rotation());
    if (q.w() < 0) q.coeffs() = -q.coeffs();
    const Eigen::Vector3d& p = T_w_c.translation();
    std::snprintf(line, sizeof(line), "%s %.9f %.9f %.9f %.9f %.9f %.9f %.9f\n", secondsText(ns).c_str(), p.x(), p.y(),
                  p.z(), q.x(), q.y(), q.z(), q.w());
    tum << line;
    std::snprintf(line, sizeof(line), "%lld,%.9f,%.9f,%.9f,%.9f,%.9f,%.9f,%.9f\n", static_cast<long long>(ns), p.x(),
                  p.y(), p.z(), q.w(), q.x(), q.y(), q.z());
    body << line;
    if (progress) progress(i + 1, frames);
  }
  if (!csv || !tum || !body) throw std::runtime_error(out_dir + ": write failed");

  std::ostringstream js;
  js.precision(12);
  js << "{\"generator\": \"vitamin_e_make_sequence\", ";
  if (street) js << "\"scene\": \"street\", ";
  js << "\"n_frames\": " << frames << ", \"rate_hz\": " << config.rate_hz
     << ", \"first_frame_ns\": " << frameTimestampNs(config, 0)
     << ", \"last_frame_ns\": " << frameTimestampNs(config, frames - 1) << ",\n \"camera\": {\"width\": " << cam.width()
     << ", \"height\": " << cam.height() << ", \"K\": [" << cam.fx() << ", " << cam.fy() << ", " << cam.cx() << ", "
     << cam.cy() << "], \"distortion_model\": \"" << camera::toString(cam.model()) << "\", \"distortion\": [";
  for (std::size_t k = 0; k < cam.distortion().size(); ++k) js << (k ? ", " : "") << cam.distortion()[k];
  js << "], \"T_B_C\": \"identity\"},\n \"path\": ";
  if (street) {
    js << drive_path->toJson();
  } else {
    const CameraPathConfig& pc = room_path->config();
    js << "{\"kind\": \"figure-eight\", \"center\": [" << pc.center.x() << ", " << pc.center.y() << ", "
       << pc.center.z() << "], \"radius_x\": " << pc.radius_x << ", \"radius_y\": " << pc.radius_y
       << ", \"height_amp\": " << pc.height_amp << ", \"speed_m_s\": " << pc.speed << ", \"heading0\": " << pc.heading0
       << ", \"heading_rate\": " << pc.heading_rate << "}";
  }
  js << ",\n \"render\": {\"supersample\": " << config.supersample
     << ", \"mip_filtering\": true, \"noise_sigma\": " << config.noise_sigma << "},\n";
  // The scene's fields (seed, room, boxes, faces) at the top level, as in the shared renderer's scene.json.
  const std::string scene_json = scene.toJson();
  js << " " << scene_json.substr(1, scene_json.size() - 2) << "}\n";
  openOut(out / "scene.json") << js.str();

  stats.frames = frames;
  stats.render_ms_mean = render_ms / frames;
  stats.write_ms_mean = write_ms / frames;
  return stats;
}

}  // namespace vitamin_e::synth
