#include <gtest/gtest.h>

#include <unistd.h>
#include <filesystem>
#include <fstream>
#include <functional>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "vitamin_e/io/dataset.h"

namespace fs = std::filesystem;
using namespace vitamin_e::io;

namespace {

constexpr int kW = 64, kH = 48;

const char* const kSensorYaml = R"(%YAML:1.0
sensor_type: camera
T_BS:
  cols: 4
  rows: 4
  data: [1.0, 0.0, 0.0, 0.1, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0]
rate_hz: 20
resolution: [64, 48]
camera_model: pinhole
intrinsics: [40.0, 41.0, 31.5, 23.5]
distortion_model: radial-tangential
distortion_coefficients: [-0.28, 0.07, 0.0002, 0.00002]
)";

const char* const kRosYaml = R"(image_width: 64
image_height: 48
camera_matrix: {rows: 3, cols: 3, data: [50.0, 0, 32.0, 0, 50.0, 24.0, 0, 0, 1]}
distortion_model: plumb_bob
distortion_coefficients: {rows: 1, cols: 5, data: [0.1, -0.01, 0, 0, 0]}
)";

class DatasetTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("ve_io_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  static void write(const fs::path& p, const std::string& text) {
    fs::create_directories(p.parent_path());
    std::ofstream(p) << text;
  }
  // A gray image whose pixels encode the frame index.
  static cv::Mat frameImage(int index, int w = kW, int h = kH) {
    cv::Mat img(h, w, CV_8UC1);
    for (int v = 0; v < h; ++v)
      for (int u = 0; u < w; ++u) img.at<uchar>(v, u) = static_cast<uchar>((u + 2 * v + 40 * index) % 256);
    return img;
  }
  // EuRoC ASL folder: dir_/seq/mav0/cam0/{data.csv,data/,sensor.yaml}.
  fs::path makeEuroc(int n = 3) {
    const fs::path cam = dir_ / "seq" / "mav0" / "cam0";
    fs::create_directories(cam / "data");
    std::string csv = "#timestamp [ns],filename\n";
    for (int i = 0; i < n; ++i) {
      const std::string ns = std::to_string(1403715273262142976ULL + 50000128ULL * i);
      csv.append(ns).append(",").append(ns).append(".png\r\n");  // CRLF as some copies have
      cv::imwrite((cam / "data" / (ns + ".png")).string(), frameImage(i));
    }
    write(cam / "data.csv", csv);
    write(cam / "sensor.yaml", kSensorYaml);
    return dir_ / "seq";
  }
  fs::path dir_;
};

// The call must throw DatasetError whose message contains every `parts`.
void expectError(const std::function<void()>& fn, const std::vector<std::string>& parts) {
  try {
    fn();
    ADD_FAILURE() << "no DatasetError (expected '" << parts.front() << "')";
  } catch (const DatasetError& e) {
    const std::string msg = e.what();
    EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
    for (const std::string& p : parts) EXPECT_NE(msg.find(p), std::string::npos) << "'" << p << "' not in: " << msg;
  }
}

}  // namespace

TEST(DatasetText, NanosecondsToSecondsIsExact) {
  EXPECT_EQ(nanosecondsToSecondsText("1403715273262142976"), "1403715273.262142976");
  EXPECT_EQ(nanosecondsToSecondsText("1403715273312143104"), "1403715273.312143104");
  EXPECT_EQ(nanosecondsToSecondsText("1000000000"), "1.000000000");
  EXPECT_EQ(nanosecondsToSecondsText("5"), "0.000000005");
  EXPECT_THROW(nanosecondsToSecondsText("12a"), DatasetError);
  EXPECT_THROW(nanosecondsToSecondsText(""), DatasetError);
}

TEST(DatasetText, ToGray8ConvertsColorAnd16Bit) {
  cv::Mat bgr(2, 2, CV_8UC3, cv::Scalar(0, 0, 255));  // pure red
  const cv::Mat g = toGray8(bgr);
  ASSERT_EQ(g.type(), CV_8UC1);
  EXPECT_NEAR(g.at<uchar>(0, 0), 76, 1);  // 0.299 * 255
  // The same pixels read as RGB are pure blue.
  EXPECT_NEAR(toGray8(bgr, vitamin_e::io::ChannelOrder::kRgb).at<uchar>(0, 0), 29, 1);  // 0.114 * 255
  cv::Mat bgra(2, 2, CV_8UC4, cv::Scalar(0, 255, 0, 7));                                // green, any alpha
  EXPECT_NEAR(toGray8(bgra).at<uchar>(1, 0), 150, 1);                                   // 0.587 * 255
  const cv::Mat mono(2, 2, CV_8UC1, cv::Scalar(9));
  EXPECT_EQ(toGray8(mono).data, mono.data) << "mono8 is passed through, not copied";
  EXPECT_THROW(toGray8(cv::Mat(2, 2, CV_8UC2)), DatasetError);
  cv::Mat deep(2, 2, CV_16UC1, cv::Scalar(51200));
  EXPECT_EQ(toGray8(deep).at<uchar>(1, 1), 200);
  EXPECT_THROW(toGray8(cv::Mat(2, 2, CV_32FC1)), DatasetError);
}

TEST_F(DatasetTest, EurocFromAnyOfItsThreeFolders) {
  const fs::path top = makeEuroc();
  for (const fs::path& p : {top, top / "mav0", top / "mav0" / "cam0"}) {
    EXPECT_EQ(detectDatasetKind(p.string()), "euroc") << p;
    const auto ds = openDataset(p.string());
    EXPECT_EQ(ds->kind(), "euroc");
    ASSERT_EQ(ds->size(), 3u);
    EXPECT_EQ(ds->timestampText(0), "1403715273.262142976");
    EXPECT_EQ(ds->timestampText(1), "1403715273.312143104");
    EXPECT_NEAR(ds->timestamp(1), 1403715273.312143104, 1e-6);
    EXPECT_NEAR(ds->timestamp(2) - ds->timestamp(0), 0.100000256, 1e-6);
    for (std::size_t i = 0; i < ds->size(); ++i) {
      const cv::Mat img = ds->loadImage(i);
      ASSERT_EQ(img.type(), CV_8UC1);
      EXPECT_EQ(cv::norm(img, frameImage(static_cast<int>(i)), cv::NORM_INF), 0.0);
    }
    EXPECT_EQ(ds->calibration().format, "euroc");
    EXPECT_DOUBLE_EQ(ds->calibration().camera.fy(), 41.0);
    EXPECT_NEAR(ds->calibration().T_b_c.translation().x(), 0.1, 1e-12);
    EXPECT_EQ(ds->groundTruthPath(), "");
  }
}

TEST_F(DatasetTest, EurocGroundTruthPrefersTheCameraTrajectory) {
  const fs::path top = makeEuroc();
  write(top / "mav0" / "state_groundtruth_estimate0" / "data.csv", "#t,x\n");
  EXPECT_NE(openDataset(top.string())->groundTruthPath().find("state_groundtruth_estimate0"), std::string::npos);
  write(top / "groundtruth_cam0_tum.txt", "# t tx ty tz qx qy qz qw\n");
  EXPECT_EQ(openDataset((top / "mav0").string())->groundTruthPath(), (top / "groundtruth_cam0_tum.txt").string());
}

TEST_F(DatasetTest, EurocCalibrationOverrideAnd16BitImages) {
  const fs::path top = makeEuroc();
  const fs::path calib = dir_ / "ost.yaml";
  write(calib, kRosYaml);
  DatasetOptions opt;
  opt.calibration_path = calib.string();
  const auto ds = openDataset(top.string(), opt);
  EXPECT_EQ(ds->calibration().format, "ros_camera_info");
  // Replace frame 1 by a 16-bit image: loaded as its high byte.
  const fs::path data = top / "mav0" / "cam0" / "data";
  cv::Mat deep;
  frameImage(1).convertTo(deep, CV_16U, 256.0);
  cv::imwrite((data / "1403715273312143104.png").string(), deep);
  EXPECT_EQ(cv::norm(ds->loadImage(1), frameImage(1), cv::NORM_INF), 0.0);
}

TEST_F(DatasetTest, TumFolder) {
  const fs::path tum = dir_ / "tum";
  std::string list = "# color images\n# file: 'rgbd_dataset_freiburg1_xyz.bag'\n# timestamp filename\n";
  const std::vector<std::string> stamps = {"1305031102.175304", "1305031102.211214", "1305031102.243211"};
  for (int i = 0; i < 3; ++i) {
    const std::string rel = "rgb/" + stamps[i] + ".png";
    fs::create_directories(tum / "rgb");
    cv::Mat bgr;
    cv::cvtColor(frameImage(i), bgr, cv::COLOR_GRAY2BGR);
    cv::imwrite((tum / rel).string(), bgr);
    list += stamps[i] + " " + rel + "\n";
  }
  write(tum / "rgb.txt", list);
  EXPECT_EQ(detectDatasetKind(tum.string()), "tum");
  expectError([&] { openDataset(tum.string()); }, {"camera.yaml", "--calib"});
  write(tum / "camera.yaml", kRosYaml);
  write(tum / "groundtruth.txt", "# ground truth\n");
  const auto ds = openDataset(tum.string());
  EXPECT_EQ(ds->kind(), "tum");
  ASSERT_EQ(ds->size(), 3u);
  EXPECT_EQ(ds->timestampText(2), "1305031102.243211");
  EXPECT_NEAR(ds->timestamp(1), 1305031102.211214, 1e-6);
  EXPECT_EQ(cv::norm(ds->loadImage(2), frameImage(2), cv::NORM_INF), 0.0);
  EXPECT_DOUBLE_EQ(ds->calibration().camera.fx(), 50.0);
  EXPECT_EQ(ds->groundTruthPath(), (tum / "groundtruth.txt").string());
  write(tum / "rgb.txt", list + "1305031102.3\n");
  expectError([&] { openDataset(tum.string()); }, {"rgb.txt", "line 7"});
}

TEST_F(DatasetTest, KittiFolderWithAndWithoutTimes) {
  const fs::path kitti = dir_ / "06";
  fs::create_directories(kitti / "image_0");
  for (int i = 0; i < 4; ++i) {
    char name[16];
    std::snprintf(name, sizeof(name), "%06d.png", i);
    cv::imwrite((kitti / "image_0" / name).string(), frameImage(i));
  }
  write(kitti / "calib.txt", "P0: 40 0 31.5 0 0 40 23.5 0 0 0 1 0\nP1: 40 0 31.5 -20 0 40 23.5 0 0 0 1 0\n");
  EXPECT_EQ(detectDatasetKind(kitti.string()), "kitti");
  auto ds = openDataset(kitti.string());
  EXPECT_EQ(ds->kind(), "kitti");
  ASSERT_EQ(ds->size(), 4u);
  EXPECT_NEAR(ds->timestamp(3), 0.3, 1e-12);
  EXPECT_EQ(ds->timestampText(3), "0.300000");
  EXPECT_EQ(cv::norm(ds->loadImage(3), frameImage(3), cv::NORM_INF), 0.0);
  EXPECT_EQ(ds->calibration().camera.width(), kW);
  EXPECT_DOUBLE_EQ(ds->calibration().camera.cx(), 31.5);
  write(kitti / "times.txt", "0.000000e+00\n1.036400e-01\n2.072800e-01\n3.109200e-01\n4.1e-01\n");
  write(kitti / "poses.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n");
  ds = openDataset(kitti.string());
  EXPECT_EQ(ds->timestampText(1), "1.036400e-01");
  EXPECT_NEAR(ds->timestamp(3), 0.31092, 1e-12);
  EXPECT_EQ(ds->groundTruthPath(), (kitti / "poses.txt").string());
  write(kitti / "times.txt", "0.0\n0.1\n");
  expectError([&] { openDataset(kitti.string()); }, {"times.txt", "2 times for 4 images"});
}

TEST_F(DatasetTest, BadInputsGiveOneClearError) {
  expectError([&] { openDataset((dir_ / "missing").string()); }, {"missing", "does not exist"});
  fs::create_directories(dir_ / "empty");
  EXPECT_EQ(detectDatasetKind((dir_ / "empty").string()), "");
  expectError([&] { openDataset((dir_ / "empty").string()); }, {"empty", "not a known dataset layout"});
  write(dir_ / "x.bag", "not a bag");
  EXPECT_EQ(detectDatasetKind((dir_ / "x.bag").string()), "rosbag");
  expectError([&] { openDataset((dir_ / "x.bag").string()); }, {"rosbag"});
  write(dir_ / "notes.txt", "hello");
  expectError([&] { openDataset((dir_ / "notes.txt").string()); }, {"not a folder"});

  const fs::path top = makeEuroc();
  const fs::path cam = top / "mav0" / "cam0";
  DatasetOptions missing_calib;
  missing_calib.calibration_path = (dir_ / "nope.yaml").string();
  expectError([&] { openDataset(top.string(), missing_calib); }, {"nope.yaml", "does not exist"});

  write(cam / "data.csv", "#timestamp [ns],filename\n\n");
  expectError([&] { openDataset(top.string()); }, {"data.csv", "lists no images"});
  write(cam / "data.csv", "#timestamp [ns],filename\n1403715273262142976 1403715273262142976.png\n");
  expectError([&] { openDataset(top.string()); }, {"data.csv", "line 2", "timestamp_ns,filename"});
  write(cam / "data.csv", "1403715273x62142976,a.png\n");
  expectError([&] { openDataset(top.string()); }, {"data.csv", "line 1"});
  write(cam / "data.csv", "1403715273312143104,1403715273312143104.png\n1403715273262142976,1403715273262142976.png\n");
  expectError([&] { openDataset(top.string()); }, {"data.csv", "do not increase"});

  // Unreadable first image (garbage bytes): open fails naming it.
  write(cam / "data.csv", "1403715273262142976,1403715273262142976.png\n1403715273312143104,1403715273312143104.png\n"
                          "1403715273362143232,1403715273362143232.png\n");
  const std::string bad = (cam / "data" / "1403715273262142976.png").string();
  write(bad, "this is not a png");
  expectError([&] { openDataset(top.string()); }, {bad, "cannot read image"});
  // Unreadable image later in the sequence: open works, loadImage names the file.
  cv::imwrite(bad, frameImage(0));
  const std::string late = (cam / "data" / "1403715273362143232.png").string();
  fs::remove(late);
  const auto ds = openDataset(top.string());
  expectError([&] { ds->loadImage(2); }, {late, "file missing"});
  EXPECT_NO_THROW(ds->loadImage(1));
  // Another size later in the sequence.
  cv::imwrite(late, frameImage(2, 32, 24));
  expectError([&] { ds->loadImage(2); }, {late, "32x24", "64x48"});

  // Calibration for another size: names both sizes and both files.
  cv::imwrite(bad, frameImage(0, 80, 60));
  expectError([&] { openDataset(top.string()); }, {bad, "80x60", "64x48", "sensor.yaml"});
  cv::imwrite(bad, frameImage(0));

  // Broken calibration file: the calibration error, as a DatasetError.
  write(cam / "sensor.yaml", "resolution: [64, 48]\n");
  expectError([&] { openDataset(top.string()); }, {"sensor.yaml", "intrinsics"});

  fs::remove_all(cam / "data");
  expectError([&] { openDataset(top.string()); }, {"cam0", "images folder"});
  fs::remove(cam / "data.csv");
  expectError([&] { openDataset(top.string()); }, {"cam0", "no data.csv"});
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
