// Synthetic sequence generator: rendered pixels agree with the scene geometry
// and ground truth, the written EuRoC folder is complete and readable, output
// is deterministic per seed, and the texture is rich and not repetitive.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "vitamin_e/camera/camera.h"
#include "vitamin_e/synth/renderer.h"
#include "vitamin_e/synth/sequence.h"

namespace vs = vitamin_e::synth;
namespace fs = std::filesystem;

namespace {

class TempDir {
 public:
  TempDir()
      : path_(fs::temp_directory_path() /
              ("ve_synth_" + std::to_string(::getpid()) + "_" + std::to_string(num_created++))) {
    fs::create_directories(path_);
  }
  ~TempDir() { fs::remove_all(path_); }
  std::string str() const { return path_.string(); }
  fs::path path() const { return path_; }

 private:
  fs::path path_;
  static inline int num_created = 0;
};

float bilinear8(const cv::Mat& img, const Eigen::Vector2d& uv) {
  const int x0 = static_cast<int>(std::floor(uv.x())), y0 = static_cast<int>(std::floor(uv.y()));
  const double ax = uv.x() - x0, ay = uv.y() - y0;
  auto at = [&](int x, int y) { return img.at<uchar>(y, x) / 255.0; };
  return static_cast<float>((1 - ay) * ((1 - ax) * at(x0, y0) + ax * at(x0 + 1, y0)) +
                            ay * ((1 - ax) * at(x0, y0 + 1) + ax * at(x0 + 1, y0 + 1)));
}

// T_w_c looking along +x from p at a slight angle (optical frame: x right, y down).
Eigen::Isometry3d lookAlongX(const Eigen::Vector3d& p, double yaw) {
  const Eigen::Vector3d f(std::cos(yaw), std::sin(yaw), 0.0), r(std::sin(yaw), -std::cos(yaw), 0.0);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() << r, f.cross(r), f;
  T.translation() = p;
  return T;
}

struct PixelCheck {
  double median_err = 0.0;          // |image - texture| at the projections
  double median_err_shifted = 0.0;  // same, 3 px off (must be much worse)
  int points = 0;
};

// Points on face `face` (random, visible, unoccluded, and near enough that a
// pixel covers less than a texel, so the renderer samples the full-resolution
// texture), projected with the camera model and T_w_c; compares image values
// with the scene's texture.
PixelCheck checkFacePoints(const vs::Scene& scene, int face, const vitamin_e::camera::Camera& cam,
                           const Eigen::Isometry3d& T_w_c, const cv::Mat& img, int wanted) {
  const vs::Face& f = scene.faces()[face];
  vs::Rng rng(42);
  std::vector<double> err, err_shift;
  for (int k = 0; k < 20000 && static_cast<int>(err.size()) < wanted; ++k) {
    Eigen::Vector3d p;
    p[f.axis] = f.plane;
    p[f.u_axis] = rng.uniform(f.lo.x(), f.hi.x());
    p[f.v_axis] = rng.uniform(f.lo.y(), f.hi.y());
    Eigen::Vector2d uv;
    if (!cam.project(T_w_c.inverse() * p, &uv) || !cam.inImage(uv, 5.0)) continue;
    // Unoccluded: the first hit towards p is p itself (independent of the renderer).
    vs::RayHit hit;
    const Eigen::Vector3d o = T_w_c.translation();
    if (!scene.intersect(o, (p - o).normalized(), &hit) || hit.face != face || (hit.p - p).norm() > 1e-6) continue;
    if (hit.t / cam.fx() / std::sqrt(hit.cos_incidence) > 0.7 * scene.config().texel_m) continue;
    const float truth = scene.textureAt(face, p);
    err.push_back(std::abs(bilinear8(img, uv) - truth));
    err_shift.push_back(std::abs(bilinear8(img, uv + Eigen::Vector2d(3.0, 0.0)) - truth));
  }
  auto median = [](std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
    return v[v.size() / 2];
  };
  PixelCheck c;
  c.points = static_cast<int>(err.size());
  if (c.points > 0) {
    c.median_err = median(err);
    c.median_err_shifted = median(err_shift);
  }
  return c;
}

std::vector<std::string> readLines(const fs::path& p) {
  std::ifstream f(p);
  std::vector<std::string> lines;
  std::string l;
  while (std::getline(f, l))
    if (!l.empty() && l[0] != '#') lines.push_back(l);
  return lines;
}

}  // namespace

TEST(SynthScene, WallPointProjectsOntoItsTextureWithLensDistortion) {
  vs::SceneConfig sc;
  sc.num_boxes = 0;
  sc.texel_m = 0.01;
  sc.seed = 5;
  const vs::Scene scene = vs::Scene::makeRoom(sc);
  const auto cam = vs::makeSequenceCamera(320, 240, true);  // EuRoC distortion, fx ~ 195 px
  const vs::Renderer renderer(scene, cam, 1);
  // 1.3 m from the +x wall (face 1): a pixel covers < 1 texel, level-0 sampling.
  const Eigen::Isometry3d T_w_c = lookAlongX(Eigen::Vector3d(2.7, 0.2, 1.4), 0.15);
  const cv::Mat img = renderer.render(T_w_c);
  ASSERT_EQ(img.type(), CV_8UC1);
  ASSERT_EQ(img.cols, 320);
  const PixelCheck c = checkFacePoints(scene, 1, cam, T_w_c, img, 400);
  ASSERT_GE(c.points, 300);
  EXPECT_LT(c.median_err, 0.01) << "rendered texture does not match the scene at the projection";
  EXPECT_GT(c.median_err_shifted, 4.0 * c.median_err) << "the check cannot tell a 3 px error";
  // Depth of the centre pixel is the distance to the wall along the optical axis.
  cv::Mat depth;
  renderer.renderFloat(T_w_c, &depth);
  Eigen::Vector3d b;
  ASSERT_TRUE(cam.unproject(Eigen::Vector2d(160, 120), &b));
  const Eigen::Vector3d d_w = T_w_c.linear() * b;
  const double t = (4.0 - 2.7) / d_w.x();
  EXPECT_NEAR(depth.at<float>(120, 160), t * b.z(), 1e-3);
}

TEST(SynthScene, RoomGeometryAndBoxesClearOfThePath) {
  vs::SequenceConfig cfg;
  cfg.seed = 3;
  const vs::CameraPath path(vs::makeSequencePath(cfg));
  const vs::Scene scene = vs::makeSequenceScene(cfg, path);
  EXPECT_EQ(scene.boxes().size(), 6u);
  EXPECT_EQ(scene.faces().size(), 6u + 6u * scene.boxes().size());
  for (const auto& p : path.samplePositions(30.0, 0.1)) {
    for (const auto& b : scene.boxes()) EXPECT_GE((p.cwiseMax(b.min).cwiseMin(b.max) - p).norm(), 0.99);
    EXPECT_TRUE((p.array() > scene.room().min.array() + 1.0).all() &&
                (p.array() < scene.room().max.array() - 1.0).all());
  }
  // Every ray from the path hits something, and the hit lies on the face reported.
  vs::Rng rng(1);
  for (int k = 0; k < 2000; ++k) {
    const Eigen::Vector3d o = path.position(rng.uniform(0.0, 20.0));
    const Eigen::Vector3d d = Eigen::Vector3d(rng.gaussian(), rng.gaussian(), rng.gaussian()).normalized();
    vs::RayHit hit;
    ASSERT_TRUE(scene.intersect(o, d, &hit));
    EXPECT_TRUE(scene.onFace(hit.face, hit.p, 1e-6));
    EXPECT_LT(scene.faces()[hit.face].normal().dot(d), 0.0);  // faces point at the viewer
  }
  // Mean speed as configured.
  double len = 0.0;
  for (int i = 0; i < 400; ++i) len += (path.position((i + 1) * 0.05) - path.position(i * 0.05)).norm();
  EXPECT_NEAR(len / 20.0, cfg.speed, 0.03);
}

TEST(SynthScene, RenderedDepthMatchesUnculledRayCasting) {
  // The renderer skips boxes outside the view cone; its depth must equal plain
  // ray casting against everything, from many poses along the path.
  vs::SequenceConfig cfg;
  cfg.seed = 4;
  cfg.num_boxes = 12;
  const vs::CameraPath path(vs::makeSequencePath(cfg));
  const vs::Scene scene = vs::makeSequenceScene(cfg, path);
  const auto cam = vs::makeSequenceCamera(160, 120, true);
  const vs::Renderer renderer(scene, cam, 1);
  int box_pixels = 0;
  for (double t = 0.0; t < 30.0; t += 1.5) {
    const Eigen::Isometry3d T_w_c = path.T_w_c(t);
    cv::Mat depth;
    renderer.renderFloat(T_w_c, &depth);
    for (int v = 0; v < 120; v += 3) {
      for (int u = 0; u < 160; u += 3) {
        Eigen::Vector3d b;
        ASSERT_TRUE(cam.unproject(Eigen::Vector2d(u, v), &b));
        vs::RayHit hit;
        ASSERT_TRUE(scene.intersect(T_w_c.translation(), T_w_c.linear() * b.normalized(), &hit));
        ASSERT_NEAR(depth.at<float>(v, u), hit.t * b.normalized().z(), 1e-3) << "t " << t << " pixel " << u << "," << v;
        if (hit.face >= 6) ++box_pixels;
      }
    }
  }
  EXPECT_GT(box_pixels, 100);  // boxes were in view
}

TEST(SynthScene, TextureIsRichAndNotRepetitive) {
  const cv::Mat tex = vs::generateProceduralTexture(800, 600, 0.005, 11);
  cv::Scalar mean, sd;
  cv::meanStdDev(tex, mean, sd);
  EXPECT_NEAR(mean[0], 0.5, 0.08);
  EXPECT_GT(sd[0], 0.1);
  // Many curvature extrema at a small scale: local maxima of the smoothed
  // determinant of the Hessian.
  cv::Mat blur, dxx, dyy, dxy;
  cv::GaussianBlur(tex, blur, cv::Size(0, 0), 2.0);
  cv::Sobel(blur, dxx, CV_32F, 2, 0);
  cv::Sobel(blur, dyy, CV_32F, 0, 2);
  cv::Sobel(blur, dxy, CV_32F, 1, 1);
  cv::Mat det = dxx.mul(dyy) - dxy.mul(dxy);
  cv::Mat dil;
  cv::dilate(det, dil, cv::Mat::ones(7, 7, CV_8U));
  int extrema = 0;
  for (int i = 4; i < det.rows - 4; ++i)
    for (int j = 4; j < det.cols - 4; ++j)
      if (det.at<float>(i, j) == dil.at<float>(i, j) && det.at<float>(i, j) > 1e-4f) ++extrema;
  EXPECT_GT(extrema, 800);  // 12 m^2 at 5 mm texels
  // Not periodic: a patch matches itself only where it came from.
  const cv::Mat patch = tex(cv::Rect(300, 250, 64, 64));
  cv::Mat score;
  cv::matchTemplate(tex, patch, score, cv::TM_CCOEFF_NORMED);
  int strong = 0;
  for (int i = 0; i < score.rows; ++i)
    for (int j = 0; j < score.cols; ++j)
      if (score.at<float>(i, j) > 0.8f && (std::abs(i - 250) > 8 || std::abs(j - 300) > 8)) ++strong;
  EXPECT_EQ(strong, 0);
  // Deterministic per seed, different across seeds.
  EXPECT_EQ(cv::norm(tex, vs::generateProceduralTexture(800, 600, 0.005, 11), cv::NORM_INF), 0.0);
  EXPECT_GT(cv::norm(tex, vs::generateProceduralTexture(800, 600, 0.005, 12), cv::NORM_L1), 1000.0);
}

TEST(SynthSequence, WritesReadableEurocFolderMatchingGroundTruth) {
  TempDir dir, dir2, dir3;
  vs::SequenceConfig cfg;
  cfg.frames = 6;
  cfg.width = 320;
  cfg.height = 240;
  cfg.seed = 9;
  cfg.noise_sigma = 0.0;
  cfg.texel_m = 0.03;  // coarse, so that most surfaces render at full texture resolution
  const vs::SequenceStats stats = vs::writeSequence(dir.str(), cfg);
  EXPECT_EQ(stats.frames, 6);
  const fs::path cam_dir = dir.path() / "mav0" / "cam0";
  const auto csv = readLines(cam_dir / "data.csv");
  ASSERT_EQ(csv.size(), 6u);
  const auto gt = readLines(dir.path() / "groundtruth_cam0_tum.txt");
  ASSERT_EQ(gt.size(), 6u);
  EXPECT_EQ(readLines(dir.path() / "mav0" / "state_groundtruth_estimate0" / "data.csv").size(), 6u);
  // scene.json is valid JSON (YAML is a superset) with the room and boxes at the top.
  const YAML::Node js = YAML::LoadFile((dir.path() / "scene.json").string());
  EXPECT_EQ(js["room"]["max"].size(), 3u);
  EXPECT_DOUBLE_EQ(js["room"]["max"][0].as<double>(), 4.0);
  EXPECT_EQ(js["n_frames"].as<int>(), 6);
  // The calibration reads back through the camera module's EuRoC loader.
  const auto calib = vitamin_e::camera::loadEurocSensorYaml((cam_dir / "sensor.yaml").string());
  const auto cam = vs::makeSequenceCamera(320, 240, true);
  EXPECT_EQ(calib.camera.width(), 320);
  EXPECT_NEAR(calib.camera.fx(), cam.fx(), 1e-6);
  EXPECT_EQ(calib.camera.model(), vitamin_e::camera::DistortionModel::kRadialTangential);
  EXPECT_NEAR(calib.camera.distortion()[0], -0.28340811, 1e-9);
  EXPECT_NEAR(calib.rate_hz, 20.0, 1e-9);

  // Frame 3: the image file named in data.csv, its pose from the TUM file.
  const std::string& row = csv[3];
  const std::string ns = row.substr(0, row.find(','));
  const cv::Mat img = cv::imread((cam_dir / "data" / row.substr(row.find(',') + 1)).string(), cv::IMREAD_UNCHANGED);
  ASSERT_FALSE(img.empty());
  ASSERT_EQ(img.type(), CV_8UC1);
  std::istringstream in(gt[3]);
  std::string t_text;
  double tx, ty, tz, qx, qy, qz, qw;
  in >> t_text >> tx >> ty >> tz >> qx >> qy >> qz >> qw;
  EXPECT_EQ(t_text, ns.substr(0, ns.size() - 9) + "." + ns.substr(ns.size() - 9));
  Eigen::Isometry3d T_w_c = Eigen::Isometry3d::Identity();
  T_w_c.linear() = Eigen::Quaterniond(qw, qx, qy, qz).normalized().toRotationMatrix();
  T_w_c.translation() = Eigen::Vector3d(tx, ty, tz);
  // The same scene as the writer's (deterministic from the config).
  const vs::CameraPath path(vs::makeSequencePath(cfg));
  const vs::Scene scene = vs::makeSequenceScene(cfg, path);
  EXPECT_EQ(js["boxes"].size(), scene.boxes().size());
  EXPECT_EQ(js["faces"].size(), scene.faces().size());
  int checked = 0;
  for (int face = 0; face < static_cast<int>(scene.faces().size()); ++face) {
    const PixelCheck c = checkFacePoints(scene, face, cam, T_w_c, img, 200);
    if (c.points < 100) continue;
    EXPECT_LT(c.median_err, 0.01) << "face " << face;
    EXPECT_GT(c.median_err_shifted, 4.0 * c.median_err) << "face " << face;
    ++checked;
  }
  EXPECT_GE(checked, 2);

  // Deterministic for a fixed seed; another seed gives another sequence.
  vs::writeSequence(dir2.str(), cfg);
  cfg.seed = 10;
  vs::writeSequence(dir3.str(), cfg);
  const auto name = row.substr(row.find(',') + 1);
  const cv::Mat again = cv::imread((dir2.path() / "mav0/cam0/data" / name).string(), cv::IMREAD_UNCHANGED);
  const cv::Mat other = cv::imread((dir3.path() / "mav0/cam0/data" / name).string(), cv::IMREAD_UNCHANGED);
  EXPECT_EQ(cv::norm(img, again, cv::NORM_INF), 0.0);
  EXPECT_GT(cv::norm(img, other, cv::NORM_L1), 1e5);
}

TEST(SynthSequence, RejectsBadConfig) {
  vs::SequenceConfig cfg;
  cfg.frames = 0;
  EXPECT_THROW(cfg.validate(), std::invalid_argument);
  cfg = vs::SequenceConfig();
  cfg.supersample = 9;
  EXPECT_THROW(cfg.validate(), std::invalid_argument);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
