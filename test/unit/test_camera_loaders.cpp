#include <gtest/gtest.h>

#include <unistd.h>
#include <filesystem>
#include <fstream>
#include <functional>

#include "vitamin_e/camera/camera.h"

namespace fs = std::filesystem;
using namespace vitamin_e::camera;

namespace {

class LoaderTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("ve_calib_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string write(const std::string& name, const std::string& text) {
    const fs::path p = dir_ / name;
    std::ofstream(p) << text;
    return p.string();
  }
  fs::path dir_;
};

const char* const kEurocYaml = R"(%YAML:1.0
# General sensor definitions.
sensor_type: camera
comment: VI-Sensor cam0 (MT9M034)
T_BS:
  cols: 4
  rows: 4
  data: [0.0148655429818, -0.999880929698, 0.00414029679422, -0.0216401454975,
         0.999557249008, 0.0149672133247, 0.025715529948, -0.064676986768,
        -0.0257744366974, 0.00375618835797, 0.999660727178, 0.00981073058949,
         0.0, 0.0, 0.0, 1.0]
rate_hz: 20
resolution: [752, 480]
camera_model: pinhole
intrinsics: [458.654, 457.296, 367.215, 248.375] #fu, fv, cu, cv
distortion_model: radial-tangential
distortion_coefficients: [-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05]
)";

const char* const kKalibr = R"(cam0:
  cam_overlaps: [1]
  camera_model: pinhole
  distortion_coeffs: [-0.0073, 0.0426, -0.0407, 0.0077]
  distortion_model: equidistant
  intrinsics: [286.1, 286.3, 424.5, 400.2]
  resolution: [848, 800]
  rostopic: /cam0/image_raw
  T_cam_imu:
  - [0.0, -1.0, 0.0, 0.1]
  - [1.0, 0.0, 0.0, 0.2]
  - [0.0, 0.0, 1.0, 0.3]
  - [0.0, 0.0, 0.0, 1.0]
cam1:
  camera_model: pinhole
  distortion_coeffs: [0.01, -0.02, 0.001, 0.002]
  distortion_model: radtan
  intrinsics: [400, 401, 320, 240]
  resolution: [640, 480]
)";

const char* const kRosInfo = R"(image_width: 640
image_height: 480
camera_name: narrow_stereo
camera_matrix:
  rows: 3
  cols: 3
  data: [520.5, 0, 321.2, 0, 518.9, 240.7, 0, 0, 1]
distortion_model: plumb_bob
distortion_coefficients:
  rows: 1
  cols: 5
  data: [-0.21, 0.05, 0.0012, -0.0008, -0.004]
rectification_matrix:
  rows: 3
  cols: 3
  data: [1, 0, 0, 0, 1, 0, 0, 0, 1]
projection_matrix:
  rows: 3
  cols: 4
  data: [500, 0, 320, 0, 0, 500, 240, 0, 0, 0, 1, 0]
)";

const char* const kKittiLabelled =
    "P0: 7.070912e+02 0 6.018873e+02 0 0 7.070912e+02 1.831104e+02 0 0 0 1 0\n"
    "P1: 7.070912e+02 0 6.018873e+02 -3.798145e+02 0 7.070912e+02 1.831104e+02 0 0 0 1 0\n"
    "Tr: 1 0 0 0 0 1 0 0 0 0 1 0\n";

}  // namespace

TEST_F(LoaderTest, EurocSensorYaml) {
  const std::string path = write("sensor.yaml", kEurocYaml);
  const CameraCalibration c = loadEurocSensorYaml(path);
  EXPECT_EQ(c.format, "euroc");
  EXPECT_EQ(c.camera.width(), 752);
  EXPECT_EQ(c.camera.height(), 480);
  EXPECT_DOUBLE_EQ(c.camera.fx(), 458.654);
  EXPECT_DOUBLE_EQ(c.camera.cy(), 248.375);
  EXPECT_EQ(c.camera.model(), DistortionModel::kRadialTangential);
  ASSERT_EQ(c.camera.distortion().size(), 4u);
  EXPECT_DOUBLE_EQ(c.camera.distortion()[0], -0.28340811);
  EXPECT_DOUBLE_EQ(c.rate_hz, 20.0);
  EXPECT_NEAR(c.T_b_c.translation().x(), -0.0216401454975, 1e-12);
  EXPECT_NEAR(c.T_b_c.translation().y(), -0.064676986768, 1e-12);
  EXPECT_NEAR(c.T_b_c.linear()(0, 1), -0.999880929698, 1e-6);
  EXPECT_NEAR(c.T_b_c.linear()(1, 0), 0.999557249008, 1e-6);
  EXPECT_NEAR((c.T_b_c.linear().transpose() * c.T_b_c.linear() - Eigen::Matrix3d::Identity()).norm(), 0.0, 1e-12);
  // Detected as EuRoC.
  EXPECT_EQ(loadCalibration(path).format, "euroc");
}

TEST_F(LoaderTest, EurocOpenCvMatrixTag) {
  const std::string path = write("cv.yaml", "%YAML:1.0\n---\nT_BS: !!opencv-matrix\n  rows: 4\n  cols: 4\n  dt: d\n"
                                            "  data: [1, 0, 0, 0.5, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]\n"
                                            "resolution: [640, 480]\nintrinsics: [500, 500, 320, 240]\n"
                                            "distortion_model: radial-tangential\n"
                                            "distortion_coefficients: [0.0, 0.0, 0.0, 0.0]\n");
  const CameraCalibration c = loadCalibration(path);
  EXPECT_EQ(c.format, "euroc");
  EXPECT_NEAR(c.T_b_c.translation().x(), 0.5, 1e-12);
  // All-zero coefficients become the pinhole model.
  EXPECT_EQ(c.camera.model(), DistortionModel::kNone);
}

TEST_F(LoaderTest, KalibrCamchain) {
  const std::string path = write("camchain.yaml", kKalibr);
  const CameraCalibration c = loadKalibrCamchain(path, 0);
  EXPECT_EQ(c.format, "kalibr");
  EXPECT_EQ(c.camera.model(), DistortionModel::kEquidistant);
  EXPECT_EQ(c.camera.width(), 848);
  EXPECT_DOUBLE_EQ(c.camera.cx(), 424.5);
  // T_b_c is T_cam_imu inverted: the IMU origin seen from the camera is (0.1, 0.2, 0.3).
  const Eigen::Vector3d imu_origin_in_cam = c.T_b_c.inverse() * Eigen::Vector3d::Zero();
  EXPECT_NEAR((imu_origin_in_cam - Eigen::Vector3d(0.1, 0.2, 0.3)).norm(), 0.0, 1e-12);
  // T_cam_imu maps body x to camera y, so camera x is body -y.
  EXPECT_NEAR((c.T_b_c.linear() * Eigen::Vector3d::UnitX() + Eigen::Vector3d::UnitY()).norm(), 0.0, 1e-12);
  EXPECT_NEAR((c.T_b_c.linear() * Eigen::Vector3d::UnitY() - Eigen::Vector3d::UnitX()).norm(), 0.0, 1e-12);
  const CameraCalibration c1 = loadKalibrCamchain(path, 1);
  EXPECT_EQ(c1.camera.model(), DistortionModel::kRadialTangential);
  EXPECT_TRUE(c1.T_b_c.isApprox(Eigen::Isometry3d::Identity()));
  EXPECT_THROW(loadKalibrCamchain(path, 2), CalibrationError);
  EXPECT_EQ(loadCalibration(path).format, "kalibr");
}

TEST_F(LoaderTest, RosCameraInfo) {
  const std::string path = write("ost.yaml", kRosInfo);
  const CameraCalibration c = loadRosCameraInfoYaml(path);
  EXPECT_EQ(c.format, "ros_camera_info");
  EXPECT_EQ(c.camera.height(), 480);
  EXPECT_DOUBLE_EQ(c.camera.fx(), 520.5);
  EXPECT_DOUBLE_EQ(c.camera.fy(), 518.9);
  EXPECT_DOUBLE_EQ(c.camera.cy(), 240.7);
  EXPECT_EQ(c.camera.model(), DistortionModel::kRadialTangential);
  ASSERT_EQ(c.camera.distortion().size(), 5u);
  EXPECT_DOUBLE_EQ(c.camera.distortion()[4], -0.004);
  EXPECT_EQ(loadCalibration(path).format, "ros_camera_info");

  std::string fisheye = kRosInfo;
  fisheye.replace(fisheye.find("plumb_bob"), 9, "equidistant");
  fisheye.replace(fisheye.find("cols: 5"), 7, "cols: 4");
  fisheye.replace(fisheye.find(", -0.004]"), 9, "]");
  EXPECT_EQ(loadCalibration(write("fe.yaml", fisheye)).camera.model(), DistortionModel::kEquidistant);
}

TEST_F(LoaderTest, KittiCalib) {
  const std::string path = write("calib.txt", kKittiLabelled);
  const CameraCalibration c = loadKittiCalib(path, 1226, 370);
  EXPECT_EQ(c.format, "kitti");
  EXPECT_EQ(c.camera.width(), 1226);
  EXPECT_DOUBLE_EQ(c.camera.fx(), 707.0912);
  EXPECT_DOUBLE_EQ(c.camera.cx(), 601.8873);
  EXPECT_DOUBLE_EQ(c.camera.cy(), 183.1104);
  EXPECT_EQ(c.camera.model(), DistortionModel::kNone);
  // Camera 1 is the right camera, 0.537 m to the right of camera 0.
  const CameraCalibration c1 = loadKittiCalib(path, 1226, 370, 1);
  EXPECT_NEAR(c1.T_b_c.translation().x(), 0.5371, 1e-3);
  EXPECT_EQ(loadCalibration(path, 1226, 370).format, "kitti");
  // Bare lines (no labels), as in some excerpts.
  const std::string bare =
      write("bare.txt", "7.070912e+02 0 6.018873e+02 0 0 7.070912e+02 1.831104e+02 0 0 0 1 0\n"
                        "7.070912e+02 0 6.018873e+02 -3.798145e+02 0 7.070912e+02 1.831104e+02 0 0 0 1 0");
  EXPECT_DOUBLE_EQ(loadCalibration(bare, 1226, 370).camera.fy(), 707.0912);
  EXPECT_NEAR(loadKittiCalib(bare, 1226, 370, 1).T_b_c.translation().x(), 0.5371, 1e-3);
}

namespace {
// The error must be a CalibrationError naming the file and containing `what`.
void expectError(const std::function<void()>& fn, const std::string& path, const std::string& what) {
  try {
    fn();
    ADD_FAILURE() << "no error for " << path << " (expected '" << what << "')";
  } catch (const CalibrationError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(path), std::string::npos) << msg;
    EXPECT_NE(msg.find(what), std::string::npos) << msg;
  }
}
}  // namespace

TEST_F(LoaderTest, MalformedFilesThrowCalibrationError) {
  const std::string missing = (dir_ / "nope.yaml").string();
  expectError([&] { loadCalibration(missing); }, missing, "cannot be opened");

  const std::string garbage = write("garbage.yaml", "intrinsics: [1, 2\n  : : {{\n");
  expectError([&] { loadCalibration(garbage); }, garbage, "yaml");

  const std::string scalar = write("scalar.yaml", "just a string\n");
  expectError([&] { loadCalibration(scalar); }, scalar, "mapping");

  const std::string unknown = write("unknown.yaml", "foo: 1\nbar: [1, 2]\n");
  expectError([&] { loadCalibration(unknown); }, unknown, "unknown calibration format");

  std::string text = kEurocYaml;
  const std::string three = write("three.yaml", text.replace(text.find("[458.654, "), 10, "["));
  expectError([&] { loadCalibration(three); }, three, "'intrinsics' must have 4 values");

  text = kEurocYaml;
  const std::string model = write("model.yaml", text.replace(text.find("radial-tangential"), 17, "omni"));
  expectError([&] { loadCalibration(model); }, model, "unsupported distortion model 'omni'");

  text = kEurocYaml;
  const std::string nan = write("word.yaml", text.replace(text.find("458.654"), 7, "fourfifty"));
  expectError([&] { loadCalibration(nan); }, nan, "must be a number");

  text = kEurocYaml;
  const std::string neg = write("neg.yaml", text.replace(text.find("458.654"), 7, "-458.6"));
  expectError([&] { loadCalibration(neg); }, neg, "focal lengths must be positive");

  text = kEurocYaml;
  const std::string coeffs = write("coeffs.yaml", text.replace(text.find("-0.28340811, "), 13, ""));
  expectError([&] { loadCalibration(coeffs); }, coeffs, "coefficients");

  text = kEurocYaml;
  const std::string nores = write("nores.yaml", text.replace(text.find("resolution"), 10, "resolutio"));
  expectError([&] { loadCalibration(nores); }, nores, "missing key 'resolution'");

  text = kEurocYaml;
  const std::string tbs = write("tbs.yaml", text.replace(text.find("0.999557249008"), 14, "5.0"));
  expectError([&] { loadCalibration(tbs); }, tbs, "not a rigid transform");

  const std::string kitti11 = write("k11.txt", "P0: 1 0 2 0 0 1 2 0 0 0 1\n");
  expectError([&] { loadCalibration(kitti11, 100, 100); }, kitti11, "12 numbers");
  const std::string kitti_ok = write("kok.txt", kKittiLabelled);
  expectError([&] { loadCalibration(kitti_ok); }, kitti_ok, "image size");
  expectError([&] { loadKittiCalib(kitti_ok, 100, 100, 3); }, kitti_ok, "P3:");

  std::string ros = kRosInfo;
  const std::string badk = write("badk.yaml", ros.replace(ros.find("0, 518.9"), 1, "7"));
  expectError([&] { loadCalibration(badk); }, badk, "camera_matrix");
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
