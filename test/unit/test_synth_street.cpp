// The street scene (street.h) and its sequences: streets laid along the path,
// rays hit the road, facades and parked cars where the layout puts them and
// nothing in the sky, the renderer's culling changes no pixel, the sky is flat
// (sensor noise only), facades are rich and not one repeated tile, output is
// deterministic per seed, and the written folder is complete and readable.
#include <gtest/gtest.h>

#include <unistd.h>

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
#include "vitamin_e/synth/street.h"

namespace vs = vitamin_e::synth;
namespace fs = std::filesystem;

namespace {

class TempDir {
 public:
  TempDir()
      : path_(fs::temp_directory_path() /
              ("ve_street_" + std::to_string(::getpid()) + "_" + std::to_string(num_created++))) {
    fs::create_directories(path_);
  }
  ~TempDir() { fs::remove_all(path_); }
  std::string str() const { return path_.string(); }
  fs::path path() const { return path_; }

 private:
  fs::path path_;
  static inline int num_created = 0;
};

const vs::DrivePath& turnPath() {
  static const vs::DrivePath p(vs::makeDrivePathConfig("turn"));
  return p;
}

vs::StreetConfig streetConfig(std::uint64_t seed = 0) {
  vs::StreetConfig c;
  c.seed = seed;
  c.texel_per_m = 0.85 / 353.5;  // matched to a 613-pixel-wide KITTI camera
  return c;
}

const vs::Scene& turnScene() {
  static const vs::Scene s = vs::makeStreetScene(streetConfig(), turnPath());
  return s;
}

const std::string& kindOfFace(const vs::Scene& s, int face) { return s.boxKind(s.faces()[face].owner); }

Eigen::Vector3d dirAt(double heading, double elevation) {
  return Eigen::Vector3d(std::cos(heading) * std::cos(elevation), std::sin(heading) * std::cos(elevation),
                         std::sin(elevation));
}

// Curvature extrema of a texture: local maxima of the smoothed |det Hessian|.
int curvatureExtrema(const cv::Mat& tex) {
  cv::Mat blur, dxx, dyy, dxy;
  cv::GaussianBlur(tex, blur, cv::Size(0, 0), 1.5);
  cv::Sobel(blur, dxx, CV_32F, 2, 0);
  cv::Sobel(blur, dyy, CV_32F, 0, 2);
  cv::Sobel(blur, dxy, CV_32F, 1, 1);
  cv::Mat det = cv::abs(dxx.mul(dyy) - dxy.mul(dxy));
  cv::Mat dil;
  cv::dilate(det, dil, cv::Mat::ones(7, 7, CV_8U));
  int n = 0;
  for (int i = 4; i < det.rows - 4; ++i)
    for (int j = 4; j < det.cols - 4; ++j)
      if (det.at<float>(i, j) == dil.at<float>(i, j) && det.at<float>(i, j) > 1e-4f) ++n;
  return n;
}

// The best normalized cross-correlation of a patch of tex with tex more than
// 32 texels away from where it came from, and the number of such places above 0.9.
std::pair<double, int> matchesElsewhere(const cv::Mat& tex, const cv::Rect& patch) {
  cv::Mat score;
  cv::matchTemplate(tex, tex(patch), score, cv::TM_CCOEFF_NORMED);
  double best = -1.0;
  int strong = 0;
  for (int i = 0; i < score.rows; ++i) {
    for (int j = 0; j < score.cols; ++j) {
      if (std::max(std::abs(i - patch.y), std::abs(j - patch.x)) <= 32) continue;
      best = std::max(best, static_cast<double>(score.at<float>(i, j)));
      if (score.at<float>(i, j) > 0.9f) ++strong;
    }
  }
  return {best, strong};
}

}  // namespace

TEST(SynthStreet, LayoutPutsThePathInTheRightLaneOfItsStreets) {
  const vs::StreetConfig cfg = streetConfig();
  const vs::StreetLayout L = vs::makeStreetLayout(cfg, turnPath());
  const vs::DrivePath& p = turnPath();
  int on_path = 0;
  for (const vs::Street& st : L.streets) {
    if (st.on_path) ++on_path;
    for (const vs::Street& o : L.streets) {
      if (&o == &st || o.axis != st.axis) continue;
      EXPECT_GE(std::abs(o.offset - st.offset), cfg.block_min_m - 1e-9) << "parallel streets too close";
    }
  }
  EXPECT_EQ(on_path, 2);            // the street before the turn (along x) and after it (along y)
  ASSERT_GE(L.streets.size(), 3u);  // and side streets
  EXPECT_EQ(L.streets[0].axis, 0);
  EXPECT_NEAR(L.streets[0].offset, 1.5, 1e-9);  // the path at y = 0 drives 1.5 m right of the centre line
  EXPECT_EQ(L.streets[1].axis, 1);
  EXPECT_NEAR(L.streets[1].offset, p.groundPosition(p.duration()).x() - 1.5, 1e-6);
  // The town reaches margin_m beyond the path.
  EXPECT_NEAR(L.min.x(), -cfg.margin_m, 1e-9);
  EXPECT_GT(L.max.y(), p.groundPosition(p.duration()).y() + cfg.margin_m - 1e-6);

  // Paths the street scene cannot hold are refused with a message.
  vs::DrivePathConfig diagonal = vs::makeDrivePathConfig("turn");
  diagonal.heading0 = 0.3;
  EXPECT_THROW(vs::makeStreetLayout(cfg, vs::DrivePath(diagonal)), std::invalid_argument);
  vs::DrivePathConfig u_turn = vs::makeDrivePathConfig("turn");  // back along a parallel street 17 m away
  u_turn.legs.insert(u_turn.legs.end(), {u_turn.legs[1], u_turn.legs[0]});
  EXPECT_THROW(vs::makeStreetLayout(cfg, vs::DrivePath(u_turn)), std::invalid_argument);
  vs::StreetConfig bad = cfg;
  bad.lane_offset_m = 4.5;  // the car would be on the kerb
  EXPECT_THROW(vs::makeStreetScene(bad, turnPath()), std::invalid_argument);
}

TEST(SynthStreet, RaysHitRoadFacadesAndCarsAndNothingInTheSky) {
  const vs::Scene& s = turnScene();
  const vs::DrivePath& p = turnPath();
  EXPECT_FALSE(s.hasRoom());
  vs::RayHit hit;
  // Along the whole path: the road right below the camera, the sky straight up.
  for (double t = 0.0; t <= p.duration(); t += 0.25) {
    const Eigen::Vector3d o = p.position(t);
    ASSERT_TRUE(s.intersect(o, Eigen::Vector3d(0, 0, -1), &hit)) << "t " << t;
    const std::string& kind = kindOfFace(s, hit.face);
    EXPECT_TRUE(kind == "road" || kind == "intersection") << kind << " at t " << t;
    EXPECT_NEAR(hit.t, o.z(), 1e-9);
    EXPECT_EQ(s.faces()[hit.face].normal(), Eigen::Vector3d(0, 0, 1));
    EXPECT_FALSE(s.intersect(o, Eigen::Vector3d(0, 0, 1), &hit)) << "t " << t;
  }
  // On the first straight, before the intersection: facades at the sidewalk's
  // outer edge, 6.5 m to the right and 9.5 m to the left (horizontal rays pass
  // over the parked cars, which are lower than the camera).
  for (double t = 0.0; t < 1.6; t += 0.1) {
    const Eigen::Vector3d o = p.position(t);
    ASSERT_LT(o.x(), 5.0);
    ASSERT_TRUE(s.intersect(o, Eigen::Vector3d(0, -1, 0), &hit));
    EXPECT_EQ(kindOfFace(s, hit.face), "building");
    EXPECT_NEAR(hit.t, 6.5, 1e-9);
    ASSERT_TRUE(s.intersect(o, Eigen::Vector3d(0, 1, 0), &hit));
    EXPECT_EQ(kindOfFace(s, hit.face), "building");
    EXPECT_NEAR(hit.t, 9.5, 1e-9);
  }
  // Parked cars: a ray from the nearest path point to the middle of a car's
  // side at 0.8 m height meets a car (that one, or one parked in front of it).
  int cars = 0, on_target = 0;
  for (int k = 0; k < static_cast<int>(s.boxes().size()); ++k) {
    if (s.boxKind(k) != "car") continue;
    const vs::AxisBox& b = s.boxes()[k];
    Eigen::Vector3d best_o;
    double best = 1e9;
    for (double t = 0.0; t <= p.duration(); t += 0.1) {
      const Eigen::Vector3d o = p.position(t);
      const double d = (o.head<2>().cwiseMax(b.min.head<2>()).cwiseMin(b.max.head<2>()) - o.head<2>()).norm();
      if (d < best) {
        best = d;
        best_o = o;
      }
    }
    if (best > 20.0) continue;
    Eigen::Vector3d target = 0.5 * (b.min + b.max);
    target.z() = 0.8;
    target.head<2>() = best_o.head<2>().cwiseMax(b.min.head<2>()).cwiseMin(b.max.head<2>());
    ASSERT_TRUE(s.intersect(best_o, (target - best_o).normalized(), &hit));
    EXPECT_EQ(kindOfFace(s, hit.face), "car");
    ++cars;
    if (s.faces()[hit.face].owner == k) ++on_target;
  }
  EXPECT_GE(cars, 5);
  EXPECT_GE(on_target, cars * 7 / 10);
  // Random rays from the path: every hit is on its face, facing the ray; steep
  // rays go over the highest roofs into the sky, downward rays always hit.
  vs::Rng rng(3);
  for (int i = 0; i < 3000; ++i) {
    const Eigen::Vector3d o = p.position(rng.uniform(0.0, p.duration()));
    const double elevation = rng.uniform(-1.5, 1.5);
    const Eigen::Vector3d d = dirAt(rng.uniform(-M_PI, M_PI), elevation);
    const bool any = s.intersect(o, d, &hit);
    if (elevation > 75.0 * M_PI / 180.0) {
      EXPECT_FALSE(any) << "a 75-degree ray hit " << kindOfFace(s, hit.face);
    }
    if (elevation < -0.02) {
      EXPECT_TRUE(any) << "a downward ray hit nothing";
    }
    if (!any) continue;
    EXPECT_TRUE(s.onFace(hit.face, hit.p, 1e-6));
    EXPECT_LT(s.faces()[hit.face].normal().dot(d), 0.0);
  }
}

TEST(SynthStreet, PathKeepsClearOfCarsAndBuildingsAndCarsHaveCarSizes) {
  const vs::Scene& s = turnScene();
  const vs::DrivePath& p = turnPath();
  double length = 0.0;
  int cars = 0;
  for (int k = 0; k < static_cast<int>(s.boxes().size()); ++k) {
    const vs::AxisBox& b = s.boxes()[k];
    const Eigen::Vector3d ext = b.max - b.min;
    if (s.boxKind(k) == "car") {
      ++cars;
      const double len = std::max(ext.x(), ext.y()), wid = std::min(ext.x(), ext.y());
      length += len;
      EXPECT_TRUE(len >= 3.9 && len <= 4.5 && wid >= 1.7 && wid <= 1.9 && ext.z() >= 1.4 && ext.z() <= 1.6)
          << len << " x " << wid << " x " << ext.z();
      EXPECT_EQ(b.min.z(), 0.0);  // on the road
    }
    if (s.boxKind(k) != "car" && s.boxKind(k) != "building") continue;
    const double clearance = s.boxKind(k) == "car" ? 1.3 : 3.0;
    for (double t = 0.0; t <= p.duration(); t += 0.05) {
      const Eigen::Vector2d g = p.groundPosition(t);
      ASSERT_GE((g.cwiseMax(b.min.head<2>()).cwiseMin(b.max.head<2>()) - g).norm(), clearance)
          << s.boxKind(k) << " " << k << " at t " << t;
    }
  }
  ASSERT_GE(cars, 20);
  EXPECT_NEAR(length / cars, 4.2, 0.1);
}

TEST(SynthStreet, RenderedDepthMatchesUnculledRayCasting) {
  // The renderer tests only the boxes that may meet each 16x16 tile's pyramid,
  // nearest first; its depth must equal plain ray casting against every box.
  const vs::Scene& s = turnScene();
  const vs::DrivePath& p = turnPath();
  const vitamin_e::camera::Camera cam = vs::makeKittiCamera(306, 92);
  const vs::Renderer renderer(s, cam);
  int sky = 0, hits = 0;
  for (double t = 0.0; t <= p.duration(); t += 1.1) {
    const Eigen::Isometry3d T_w_c = p.T_w_c(t);
    cv::Mat depth;
    renderer.renderFloat(T_w_c, &depth);
    for (int v = 0; v < 92; v += 2) {
      for (int u = 0; u < 306; u += 2) {
        Eigen::Vector3d b;
        ASSERT_TRUE(cam.unproject(Eigen::Vector2d(u, v), &b));
        vs::RayHit hit;
        if (!s.intersect(T_w_c.translation(), T_w_c.linear() * b.normalized(), &hit)) {
          ASSERT_EQ(depth.at<float>(v, u), 0.0f) << "t " << t << " pixel " << u << "," << v;
          ++sky;
          continue;
        }
        ASSERT_NEAR(depth.at<float>(v, u), hit.t * b.normalized().z(), 1e-3 * hit.t)
            << "t " << t << " pixel " << u << "," << v;
        ++hits;
      }
    }
  }
  EXPECT_GT(sky, 1000);
  EXPECT_GT(hits, 10 * sky);
}

TEST(SynthStreet, SkyIsFlatWithSensorNoiseOnly) {
  const vs::Scene& s = turnScene();
  const vitamin_e::camera::Camera cam = vs::makeKittiCamera(613, 185);
  const vs::Renderer renderer(s, cam);
  const Eigen::Isometry3d T_w_c = turnPath().T_w_c(1.0);
  cv::Mat depth;
  const cv::Mat clean = renderer.renderFloat(T_w_c, &depth);
  vs::RenderOptions noisy;
  noisy.noise_sigma = 1.5;
  noisy.noise_seed = 11;
  const cv::Mat img = renderer.render(T_w_c, noisy);
  const cv::Mat sky_mask = depth == 0.0f;
  const int n_sky = cv::countNonZero(sky_mask);
  ASSERT_GT(n_sky, 613 * 185 / 30) << "too little sky in view";
  // Noise-free: every sky pixel is the sky intensity exactly; with noise, the
  // sky is that intensity plus the noise alone.
  double lo, hi;
  cv::minMaxLoc(clean, &lo, &hi, nullptr, nullptr, sky_mask);
  EXPECT_EQ(lo, s.skyIntensity());
  EXPECT_EQ(hi, s.skyIntensity());
  cv::Scalar mean, sd;
  cv::meanStdDev(img, mean, sd, sky_mask);
  EXPECT_NEAR(mean[0], 255.0 * s.skyIntensity(), 0.2);
  EXPECT_NEAR(sd[0], 1.5, 0.15);
  // The sky is above everything else in each column (no holes in the town below it).
  for (int u = 0; u < 613; ++u) {
    int v = 0;
    while (v < 185 && sky_mask.at<uchar>(v, u)) ++v;
    for (; v < 185; ++v) ASSERT_FALSE(sky_mask.at<uchar>(v, u)) << "sky below the skyline at " << u << "," << v;
  }
  // The rest is textured: the check above would notice a textured sky.
  const cv::Mat town_mask = ~sky_mask;
  cv::meanStdDev(img, mean, sd, town_mask);
  EXPECT_GT(sd[0], 15.0);
}

TEST(SynthStreet, FacadesAreRichAndNotOneRepeatedTile) {
  const vs::Scene& s = turnScene();
  // The three street facades with the most texels at the finest texel (near the path).
  std::vector<std::pair<int, int>> facades;  // (texels, face)
  for (int f = 0; f < static_cast<int>(s.faces().size()); ++f) {
    const vs::Face& face = s.faces()[f];
    if (kindOfFace(s, f) != "building" || face.axis == 2 || face.texture.texelSize() > 0.0201) continue;
    facades.emplace_back(face.texture.width() * face.texture.height(), f);
  }
  ASSERT_GE(facades.size(), 3u);
  std::sort(facades.rbegin(), facades.rend());
  vs::Rng rng(5);
  int patches = 0, repeated = 0;
  double extrema_per_kilotexel = 1e9;
  std::vector<cv::Mat> textures;
  for (int k = 0; k < 3; ++k) {
    cv::Mat tex;
    s.faces()[facades[k].second].texture.level(0).convertTo(tex, CV_32F, 1.0 / 65535.0);
    ASSERT_GT(tex.total(), 200000u);
    textures.push_back(tex);
    // Many curvature extrema at the scale of a few texels (2 cm).
    extrema_per_kilotexel =
        std::min(extrema_per_kilotexel, 1000.0 * curvatureExtrema(tex) / static_cast<double>(tex.total()));
    // Patches of 1.3 m: windows repeat, but most patches match nowhere else
    // and none matches elsewhere perfectly (as a repeated tile would).
    for (int n = 0; n < 8; ++n, ++patches) {
      const cv::Rect patch(static_cast<int>(rng.uniform(0, tex.cols - 64)),
                           static_cast<int>(rng.uniform(0, tex.rows - 64)), 64, 64);
      const auto [best, strong] = matchesElsewhere(tex, patch);
      EXPECT_LT(best, 0.985) << "face " << facades[k].second << " patch at " << patch.x << "," << patch.y;
      if (strong > 0) ++repeated;
    }
  }
  EXPECT_GT(extrema_per_kilotexel, 4.0);
  EXPECT_LE(repeated, patches / 2);
  // The check sees a repeated tile.
  cv::Mat tiled;
  cv::repeat(textures[0](cv::Rect(0, 0, 150, 150)), 4, 4, tiled);
  int tiled_repeated = 0;
  for (int n = 0; n < 8; ++n) {
    const cv::Rect patch(static_cast<int>(rng.uniform(0, tiled.cols - 64)),
                         static_cast<int>(rng.uniform(0, tiled.rows - 64)), 64, 64);
    const auto [best, strong] = matchesElsewhere(tiled, patch);
    if (strong > 0 && best > 0.999) ++tiled_repeated;
  }
  EXPECT_EQ(tiled_repeated, 8);
}

TEST(SynthStreet, DeterministicPerSeed) {
  const vs::Scene again = vs::makeStreetScene(streetConfig(), turnPath());
  const vs::Scene other = vs::makeStreetScene(streetConfig(1), turnPath());
  EXPECT_EQ(again.toJson(), turnScene().toJson());
  EXPECT_NE(other.toJson(), turnScene().toJson());
  const vitamin_e::camera::Camera cam = vs::makeKittiCamera(306, 92);
  vs::RenderOptions o;
  o.noise_sigma = 1.0;
  o.noise_seed = 4;
  const Eigen::Isometry3d T = turnPath().T_w_c(5.0);
  const cv::Mat a = vs::Renderer(turnScene(), cam).render(T, o);
  const cv::Mat b = vs::Renderer(again, cam).render(T, o);
  const cv::Mat c = vs::Renderer(other, cam).render(T, o);
  EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0);
  EXPECT_GT(cv::norm(a, c, cv::NORM_L1), 1e5);
}

TEST(SynthStreet, WritesAReadableSequence) {
  TempDir dir;
  vs::SequenceConfig cfg = vs::defaultSequenceConfig("street");
  EXPECT_EQ(cfg.width, 1226);
  EXPECT_EQ(cfg.height, 370);
  EXPECT_EQ(cfg.rate_hz, 10.0);
  cfg.path = "turn";
  cfg.frames = 3;
  cfg.width = 306;
  cfg.height = 92;
  cfg.noise_sigma = 0.0;
  const vs::SequenceStats stats = vs::writeSequence(dir.str(), cfg);
  EXPECT_EQ(stats.frames, 3);
  const fs::path cam_dir = dir.path() / "mav0" / "cam0";
  const auto calib = vitamin_e::camera::loadEurocSensorYaml((cam_dir / "sensor.yaml").string());
  EXPECT_EQ(calib.camera.width(), 306);
  EXPECT_NEAR(calib.camera.fx(), 707.0912 * 306 / 1226.0, 1e-6);
  EXPECT_NEAR(calib.camera.cy(), (183.1104 + 0.5) * 92 / 370.0 - 0.5, 1e-6);
  for (const double d : calib.camera.distortion()) EXPECT_EQ(d, 0.0);
  EXPECT_NEAR(calib.rate_hz, 10.0, 1e-12);
  const YAML::Node js = YAML::LoadFile((dir.path() / "scene.json").string());
  EXPECT_EQ(js["scene"].as<std::string>(), "street");
  EXPECT_EQ(js["path"]["name"].as<std::string>(), "turn");
  EXPECT_FALSE(js["room"]);
  EXPECT_GE(js["street"]["streets"].size(), 2u);
  EXPECT_EQ(js["boxes"][0]["kind"].as<std::string>().empty(), false);
  // Frame 2: the image the renderer gives for the path's pose (same scene in
  // memory), and that pose in the TUM ground truth.
  std::ifstream csv(cam_dir / "data.csv"), tum(dir.path() / "groundtruth_cam0_tum.txt");
  std::string line, name, gt;
  for (int i = 0; std::getline(csv, line);)
    if (line[0] != '#' && i++ == 2) name = line.substr(line.find(',') + 1);
  for (int i = 0; std::getline(tum, line);)
    if (line[0] != '#' && i++ == 2) gt = line;
  ASSERT_FALSE(name.empty());
  const cv::Mat img = cv::imread((cam_dir / "data" / name).string(), cv::IMREAD_UNCHANGED);
  const vs::DrivePath path(vs::makeDrivePathConfig("turn"));
  const vitamin_e::camera::Camera cam = vs::sequenceCamera(cfg);
  const vs::Scene scene = vs::makeStreetSequenceScene(cfg, path, cam);
  const cv::Mat expected = vs::Renderer(scene, cam).render(path.T_w_c(0.2));
  ASSERT_EQ(img.type(), CV_8UC1);
  EXPECT_EQ(cv::norm(img, expected, cv::NORM_INF), 0.0);
  std::istringstream in(gt);
  std::string t_text;
  double tx, ty, tz;
  in >> t_text >> tx >> ty >> tz;
  EXPECT_NEAR((Eigen::Vector3d(tx, ty, tz) - path.position(0.2)).norm(), 0.0, 1e-8);

  // Bad configurations.
  vs::SequenceConfig bad = cfg;
  bad.frames = 10000;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
  bad = cfg;
  bad.path = "zigzag";
  EXPECT_THROW(bad.validate(), std::invalid_argument);
  bad = cfg;
  bad.distortion = true;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
  EXPECT_THROW(vs::defaultSequenceConfig("forest"), std::invalid_argument);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
