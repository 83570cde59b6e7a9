// The offline runner (vitamin_e_run, built next to this test) on bad and good
// input: bad input gives exactly one "error: ..." line and exit code 2.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <sstream>

#include <yaml-cpp/yaml.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "tool_process.h"

namespace fs = std::filesystem;

namespace {

using Result = vitamin_e::test::ToolResult;

class RunnerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    runner_ = vitamin_e::test::toolNextToTest("vitamin_e_run");
    // A missing runner or tool is a failure, never a skip: a skipped test would let CI pass untested.
    ASSERT_TRUE(fs::exists(runner_)) << "vitamin_e_run not built (" << runner_ << ")";
    dir_ = vitamin_e::test::freshTestDir("ve_runner_");
  }
  void TearDown() override {
    if (!dir_.empty()) fs::remove_all(dir_);
  }
  Result run(const std::string& args) { return vitamin_e::test::runTool(runner_, args, dir_); }
  // Exit code 2 and a single "error: ..." line containing `what`.
  void expectBadInput(const std::string& args, const std::string& what) {
    vitamin_e::test::expectBadInput(run(args), args, what);
  }
  static void write(const fs::path& p, const std::string& text) {
    fs::create_directories(p.parent_path());
    std::ofstream(p) << text;
  }
  // A tiny EuRoC folder of textured images (a slow pan over a noise pattern).
  fs::path makeEuroc(int n, int w = 160, int h = 120) {
    const fs::path cam = dir_ / "seq" / "mav0" / "cam0";
    fs::create_directories(cam / "data");
    cv::Mat big(h * 2, w * 2, CV_8UC1);
    cv::randu(big, 0, 255);
    cv::GaussianBlur(big, big, cv::Size(0, 0), 2.0);
    cv::normalize(big, big, 0, 255, cv::NORM_MINMAX);
    std::string csv = "#timestamp [ns],filename\n";
    for (int i = 0; i < n; ++i) {
      const std::string ns = std::to_string(1403715273262142976ULL + 50000000ULL * i);
      csv.append(ns).append(",").append(ns).append(".png\n");
      cv::imwrite((cam / "data" / (ns + ".png")).string(), big(cv::Rect(i, i / 2, w, h)).clone());
    }
    write(cam / "data.csv", csv);
    write(cam / "sensor.yaml", "%YAML:1.0\nresolution: [" + std::to_string(w) + ", " + std::to_string(h) +
                                   "]\ncamera_model: pinhole\nintrinsics: [150, 150, " + std::to_string(w / 2) + ", " +
                                   std::to_string(h / 2) +
                                   "]\ndistortion_model: radial-tangential\n"
                                   "distortion_coefficients: [-0.1, 0.01, 0, 0]\nrate_hz: 20\n");
    return dir_ / "seq";
  }

  fs::path runner_;
  fs::path dir_;
};

}  // namespace

TEST_F(RunnerTest, BadArgumentsExitWithCode2) {
  expectBadInput("", "--dataset");
  expectBadInput("--dataset " + dir_.string(), "--out");
  expectBadInput("--dataset x --out y --bogus 1", "unknown option '--bogus'");
  expectBadInput("--dataset x --out y --max-frames -3", "--max-frames");
  expectBadInput("--dataset x --out y --stride 0", "--stride needs a positive integer");
  expectBadInput("--dataset x --out", "--out needs a value");
}

TEST_F(RunnerTest, BadDatasetsExitWithCode2) {
  const std::string out = " --out " + (dir_ / "out").string();
  expectBadInput("--dataset " + (dir_ / "missing").string() + out, "does not exist");
  fs::create_directories(dir_ / "empty");
  expectBadInput("--dataset " + (dir_ / "empty").string() + out, "not a known dataset layout");

  const fs::path top = makeEuroc(4);
  const fs::path cam = top / "mav0" / "cam0";
  expectBadInput("--dataset " + top.string() + out + " --start-frame 4", "past the end");
  expectBadInput("--dataset " + top.string() + out + " --config " + (dir_ / "none.yaml").string(), "none.yaml");
  write(dir_ / "bad.yaml", "this_key_does_not_exist: 3\n");
  expectBadInput("--dataset " + top.string() + out + " --config " + (dir_ / "bad.yaml").string(),
                 "this_key_does_not_exist");
  expectBadInput("--dataset " + top.string() + out + " --calib " + (dir_ / "nocalib.yaml").string(), "nocalib.yaml");

  const std::string csv_text = [&] {
    std::ifstream in(cam / "data.csv");
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
  }();
  write(cam / "data.csv", "#timestamp [ns],filename\n");
  expectBadInput("--dataset " + top.string() + out, "lists no images");
  write(cam / "data.csv", "#timestamp [ns],filename\n1403715273262142976;x.png\n");
  expectBadInput("--dataset " + top.string() + out, "line 2");
  write(cam / "data.csv", csv_text);

  const fs::path first = cam / "data" / "1403715273262142976.png";
  const cv::Mat keep = cv::imread(first.string(), cv::IMREAD_UNCHANGED);
  write(first, "garbage");
  expectBadInput("--dataset " + top.string() + out, "cannot read image");
  cv::imwrite(first.string(), cv::Mat(60, 80, CV_8UC1, cv::Scalar(7)));
  expectBadInput("--dataset " + top.string() + out, "80x60");
  cv::imwrite(first.string(), keep);

  write(dir_ / "file.txt", "x");
  expectBadInput("--dataset " + top.string() + " --out " + (dir_ / "file.txt").string(), "output folder");
}

TEST_F(RunnerTest, RunsASequenceAndSkipsAnUnreadableFrame) {
  const fs::path top = makeEuroc(12);
  // Frame 5 unreadable: warned, skipped, the run goes on.
  write(top / "mav0" / "cam0" / "data" / "1403715273512142976.png", "broken");
  const fs::path out = dir_ / "out";
  const Result r = run("--dataset " + top.string() + " --out " + out.string() + " --quiet");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("warning: "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("1403715273512142976.png"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("error"), std::string::npos) << r.err;
  ASSERT_TRUE(fs::exists(out / "trajectory.txt"));
  ASSERT_TRUE(fs::exists(out / "points.ply"));
  ASSERT_TRUE(fs::exists(out / "stats.json"));
  const YAML::Node j = YAML::LoadFile((out / "stats.json").string());
  EXPECT_EQ(j["frames"].as<int>(), 11);
  EXPECT_EQ(j["skipped_frames"].as<int>(), 1);
  EXPECT_LE(j["tracked_frames"].as<int>(), 11);
  EXPECT_EQ(j["timing_ms"]["total"]["count"].as<int>(), 11);
  EXPECT_GT(j["peak_rss_mb"].as<double>(), 1.0);
  // Every trajectory line: a dataset timestamp text and 7 finite numbers.
  std::ifstream traj(out / "trajectory.txt");
  std::string line;
  int poses = 0;
  while (std::getline(traj, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream ls(line);
    std::string stamp;
    ls >> stamp;
    EXPECT_EQ(stamp.rfind("1403715273.", 0), 0u) << line;
    EXPECT_EQ(stamp.size(), 20u) << line;
    double v;
    int k = 0;
    while (ls >> v) ++k;
    EXPECT_EQ(k, 7) << line;
    ++poses;
  }
  EXPECT_EQ(poses, j["tracked_frames"].as<int>());

  // --start-frame/--max-frames select a range.
  const Result r2 = run("--dataset " + (top / "mav0").string() + " --out " + out.string() +
                        " --quiet --start-frame 6 --max-frames 3");
  ASSERT_EQ(r2.code, 0) << r2.err;
  EXPECT_EQ(YAML::LoadFile((out / "stats.json").string())["frames"].as<int>(), 3);

  // --stride 2 in that range: frames 6, 8 and 10 only, in order.
  const Result r3 = run("--dataset " + (top / "mav0").string() + " --out " + out.string() +
                        " --quiet --log-frames --start-frame 6 --max-frames 5 --stride 2");
  ASSERT_EQ(r3.code, 0) << r3.err;
  const YAML::Node j3 = YAML::LoadFile((out / "stats.json").string());
  EXPECT_EQ(j3["frames"].as<int>(), 3);
  EXPECT_EQ(j3["stride"].as<int>(), 2);
  std::istringstream log(r3.out);
  std::vector<double> stamps;
  for (std::string line; std::getline(log, line);) {
    std::istringstream ls(line);
    std::string index;
    double stamp = 0.0;
    if (ls >> index >> stamp) stamps.push_back(stamp);
  }
  ASSERT_EQ(stamps.size(), 3u) << r3.out;
  for (std::size_t k = 0; k < 3; ++k) EXPECT_NEAR(stamps[k], 1403715273.562143 + 0.1 * k, 1e-5) << r3.out;

  // --pipelined reads the images ahead on another thread: the same frames, in order, the
  // unreadable one skipped with its warning, and CPU times per stage in stats.json.
  const Result r4 = run("--dataset " + top.string() + " --out " + out.string() +
                        " --quiet --pipelined --log-frames --start-frame 1 --stride 2");
  ASSERT_EQ(r4.code, 0) << r4.err;
  EXPECT_NE(r4.err.find("1403715273512142976.png"), std::string::npos) << r4.err;
  const YAML::Node j4 = YAML::LoadFile((out / "stats.json").string());
  EXPECT_EQ(j4["frames"].as<int>(), 5);  // frames 1, 3, 5, 7, 9, 11 less the unreadable 5
  EXPECT_EQ(j4["skipped_frames"].as<int>(), 1);
  EXPECT_EQ(j4["timing_ms"]["image_load"]["count"].as<int>(), 5);
  for (const char* stage : {"image_load", "tracking", "mapping"}) {
    EXPECT_GE(j4["cpu_ms"][stage].as<double>(), 0.0) << stage;
  }
  std::istringstream log4(r4.out);
  std::vector<double> stamps4;
  for (std::string line; std::getline(log4, line);) {
    std::istringstream ls(line);
    std::string index;
    double stamp = 0.0;
    if (ls >> index >> stamp) stamps4.push_back(stamp);
  }
  ASSERT_EQ(stamps4.size(), 5u) << r4.out;
  const std::vector<int> frames4 = {1, 3, 7, 9, 11};
  for (std::size_t k = 0; k < 5; ++k) {
    EXPECT_NEAR(stamps4[k], 1403715273.262143 + 0.05 * frames4[k], 1e-5) << r4.out;
  }
}

namespace {
// Writes a bag with one uniform image per encoding, written out of stamp order,
// plus a message on another topic. Needs Debian's python3 rosbag.
constexpr char kBagWriter[] = R"(import struct, sys
import rosbag, rospy
from sensor_msgs.msg import Image
from std_msgs.msg import String
W, H = 40, 30
frames = [("mono8", 40), ("mono16", 60), ("rgb8", 80), ("bgr8", 100), ("32FC1", 120), ("mono8", 140)]
bag = rosbag.Bag(sys.argv[1], "w")
for k in [3, 0, 5, 1, 4, 2]:
    enc, v = frames[k]
    m = Image()
    m.header.stamp = rospy.Time(1000, 50000000 * k)
    m.header.frame_id = "cam0"
    m.height, m.width, m.encoding, m.is_bigendian = H, W, enc, 0
    n = W * H
    if enc == "mono8":
        m.step, m.data = W, bytes([v]) * n
    elif enc == "mono16":
        m.step, m.data = 2 * W, struct.pack("<%dH" % n, *([v * 256 + 77] * n))
    elif enc in ("rgb8", "bgr8"):
        m.step, m.data = 3 * W, bytes([v, v, v]) * n
    else:
        m.step, m.data = 4 * W, struct.pack("<%df" % n, *([0.5] * n))
    bag.write("/cam0/image_raw", m, rospy.Time(2000 + k))
bag.write("/other", String(data="x"), rospy.Time(2000))
bag.close()
)";
}  // namespace

TEST_F(RunnerTest, ReadsRosbagsWithEveryEncoding) {
  write(dir_ / "write_bag.py", kBagWriter);
  const fs::path bag = dir_ / "t.bag";
  const std::string py = "/usr/bin/python3 " + (dir_ / "write_bag.py").string() + " " + bag.string() + " 2>/dev/null";
  ASSERT_TRUE(std::system(py.c_str()) == 0 && fs::exists(bag))
      << "cannot write a bag with python3 rosbag (scripts/setup.sh installs python3-rosbag)";
  write(dir_ / "calib.yaml", "image_width: 40\nimage_height: 30\n"
                             "camera_matrix: {rows: 3, cols: 3, data: [30, 0, 20, 0, 30, 15, 0, 0, 1]}\n"
                             "distortion_model: plumb_bob\ndistortion_coefficients: [0, 0, 0, 0, 0]\n");
  const std::string calib = " --calib " + (dir_ / "calib.yaml").string();
  const fs::path listing = dir_ / "frames.txt";
  const std::string cmd = runner_.string() + " --check --dataset " + bag.string() + calib + " >" + listing.string() +
                          " 2>" + (dir_ / "err.txt").string();
  const int status = std::system(cmd.c_str());
  // The package always builds the ROS layer (catkin), so the runner reads bags.
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << std::ifstream(dir_ / "err.txt").rdbuf();
  std::ifstream in(listing);
  std::vector<std::string> lines;
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  // Sorted by header stamp, exact stamp text, every encoding as gray; 32FC1 skipped with a warning.
  const std::vector<std::string> want = {"0 1000.000000000 40x30 40.00", "1 1000.050000000 40x30 60.00",
                                         "2 1000.100000000 40x30 80.00", "3 1000.150000000 40x30 100.00",
                                         "5 1000.250000000 40x30 140.00"};
  EXPECT_EQ(lines, want);
  std::ifstream e(dir_ / "err.txt");
  const std::string err((std::istreambuf_iterator<char>(e)), std::istreambuf_iterator<char>());
  EXPECT_NE(err.find("warning: "), std::string::npos) << err;
  EXPECT_NE(err.find("32FC1"), std::string::npos) << err;

  const std::string out = " --out " + (dir_ / "out").string();
  expectBadInput("--dataset " + bag.string() + out, "calibration file is required");
  expectBadInput("--dataset " + bag.string() + out + calib + " --topic /cam1/image_raw", "/cam0/image_raw");
  expectBadInput("--dataset " + bag.string() + out + calib + " --topic /other", "no sensor_msgs/Image");
  {
    std::ifstream full(bag, std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(full)), std::istreambuf_iterator<char>());
    std::ofstream(dir_ / "cut.bag", std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  }
  expectBadInput("--dataset " + (dir_ / "cut.bag").string() + out + calib, "cut.bag");
  write(dir_ / "small.yaml", "image_width: 20\nimage_height: 30\n"
                             "camera_matrix: {rows: 3, cols: 3, data: [30, 0, 10, 0, 30, 15, 0, 0, 1]}\n");
  expectBadInput("--dataset " + bag.string() + out + " --calib " + (dir_ / "small.yaml").string(), "20x30");
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
