// The offline runner (vitamin_e_run, built next to this test) stopped by SIGINT
// or SIGTERM in the middle of a run on a generated sequence: it must finish the
// current frame, write trajectory.txt, points.ply and stats.json (well-formed,
// finite, marked interrupted) and exit 0, within seconds (no hang).
#include <gtest/gtest.h>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <thread>

#include <yaml-cpp/yaml.h>

#include "vitamin_e/synth/sequence.h"

namespace fs = std::filesystem;

namespace {

std::string readFile(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

class RunnerSignal : public ::testing::Test {
 protected:
  static constexpr int kRendered = 40;
  static constexpr int kListed = 4000;  // far more than a test can process: the run is always cut

  static void SetUpTestSuite() {
    runner_ = fs::read_symlink("/proc/self/exe").parent_path() / "vitamin_e_run";
    dir_ = fs::temp_directory_path() / ("ve_runner_signal_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    if (!fs::exists(runner_)) return;
    vitamin_e::synth::SequenceConfig seq;
    seq.frames = kRendered;
    seq.width = 376;
    seq.height = 240;
    seq.seed = 2;
    vitamin_e::synth::writeSequence((dir_ / "seq").string(), seq);
    // The images listed back and forth (0..39, 38..1, 0..) with increasing stamps:
    // a long, continuous sequence from a few rendered frames.
    const fs::path cam = dir_ / "seq" / "mav0" / "cam0";
    std::vector<std::string> names;
    {
      std::ifstream in(cam / "data.csv");
      for (std::string line; std::getline(in, line);) {
        if (line.empty() || line[0] == '#') continue;
        names.push_back(line.substr(line.find(',') + 1));
      }
    }
    ASSERT_EQ(names.size(), static_cast<std::size_t>(kRendered));
    std::ofstream csv(cam / "data.csv");
    csv << "#timestamp [ns],filename\n";
    const int period = 2 * (kRendered - 1);
    for (int i = 0; i < kListed; ++i) {
      const int k = i % period;
      const int idx = k < kRendered ? k : period - k;
      csv << (1600000000000000000LL + 50000000LL * i) << "," << names[idx] << "\n";
    }
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }

  void SetUp() override {
    ASSERT_TRUE(fs::exists(runner_)) << "vitamin_e_run not built (" << runner_ << ")";  // a failure, not a skip
    ASSERT_TRUE(fs::exists(dir_ / "seq" / "mav0" / "cam0" / "data.csv"));
  }

  // Starts the runner, waits until it has processed a few frames, sends `sig`,
  // and waits (at most 60 s) for it to exit. Returns the exit status.
  int runAndSignal(int sig, const fs::path& out, std::string* err) {
    const fs::path err_path = out.string() + ".stderr";
    const pid_t pid = ::fork();
    if (pid == 0) {
      std::freopen("/dev/null", "r", stdin);
      std::freopen("/dev/null", "w", stdout);
      std::freopen(err_path.c_str(), "w", stderr);
      const std::string dataset = (dir_ / "seq").string(), out_dir = out.string(), runner = runner_.string();
      ::execl(runner.c_str(), runner.c_str(), "--dataset", dataset.c_str(), "--out", out_dir.c_str(), nullptr);
      std::_Exit(127);
    }
    EXPECT_GT(pid, 0);
    if (pid <= 0) return -1;
    // Not quiet and not a terminal: a dataset line, a camera line, then one
    // progress line right after the first frame.
    const auto start = std::chrono::steady_clock::now();
    auto seconds = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(); };
    bool started = false;
    while (seconds() < 60.0) {
      const std::string text = readFile(err_path);
      std::size_t lines = 0, pos = 0;
      while ((pos = text.find("[vitamin_e_run]", pos)) != std::string::npos) {
        ++lines;
        ++pos;
      }
      if (lines >= 3) {
        started = true;
        break;
      }
      int status = 0;
      if (::waitpid(pid, &status, WNOHANG) == pid) {
        *err = readFile(err_path);
        ADD_FAILURE() << "runner exited before the signal: " << *err;
        return status;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    EXPECT_TRUE(started) << "runner processed no frame in 60 s: " << readFile(err_path);
    std::this_thread::sleep_for(std::chrono::milliseconds(1500));  // a few more frames
    ::kill(pid, sig);
    const auto signalled = std::chrono::steady_clock::now();
    int status = 0;
    while (::waitpid(pid, &status, WNOHANG) != pid) {
      if (std::chrono::steady_clock::now() - signalled > std::chrono::seconds(60)) {
        ::kill(pid, SIGKILL);
        ::waitpid(pid, &status, 0);
        ADD_FAILURE() << "runner still running 60 s after the signal (hang)";
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    *err = readFile(err_path);
    return status;
  }

  void expectCompleteOutputs(const fs::path& out, const std::string& err) {
    ASSERT_TRUE(fs::exists(out / "stats.json")) << err;
    ASSERT_TRUE(fs::exists(out / "trajectory.txt")) << err;
    ASSERT_TRUE(fs::exists(out / "points.ply")) << err;
    EXPECT_NE(err.find("interrupted"), std::string::npos) << err;

    const YAML::Node stats = YAML::LoadFile((out / "stats.json").string());
    EXPECT_TRUE(stats["interrupted"].as<bool>());
    const int frames = stats["frames"].as<int>();
    EXPECT_GE(frames, 2) << "stopped before a few frames were processed";
    EXPECT_LT(frames, kListed) << "the run was not cut short";
    EXPECT_EQ(stats["timing_ms"]["total"]["count"].as<int>(), frames);

    // trajectory.txt: a header, then "stamp tx ty tz qx qy qz qw" with finite
    // numbers, unit quaternions and increasing stamps.
    std::ifstream traj(out / "trajectory.txt");
    std::string line;
    int poses = 0;
    double last_t = -1.0;
    while (std::getline(traj, line)) {
      if (line.empty() || line[0] == '#') continue;
      std::istringstream ls(line);
      double v[8];
      int k = 0;
      while (k < 8 && ls >> v[k]) ++k;
      std::string rest;
      ls >> rest;
      ASSERT_EQ(k, 8) << "bad line: " << line;
      EXPECT_TRUE(rest.empty()) << "extra fields: " << line;
      for (double x : v) ASSERT_TRUE(std::isfinite(x)) << line;
      EXPECT_NEAR(v[4] * v[4] + v[5] * v[5] + v[6] * v[6] + v[7] * v[7], 1.0, 1e-6) << line;
      EXPECT_GT(v[0], last_t) << line;
      last_t = v[0];
      ++poses;
    }
    EXPECT_LE(poses, frames);
    std::printf("interrupted after %d frames: %d poses, %zu map points\n", frames, poses,
                stats["map_points"].as<std::size_t>());
    EXPECT_EQ(stats["map_points"].as<std::size_t>() > 0, poses > 0);

    // points.ply: a complete header and exactly `n` binary vertices (15 bytes each).
    const std::string ply = readFile(out / "points.ply");
    const std::size_t end = ply.find("end_header\n");
    ASSERT_NE(end, std::string::npos) << "no PLY header";
    ASSERT_EQ(ply.rfind("ply\n", 0), 0u);
    const std::size_t at = ply.find("element vertex ");
    ASSERT_NE(at, std::string::npos);
    const std::size_t n = std::stoul(ply.substr(at + 15));
    EXPECT_EQ(n, stats["map_points"].as<std::size_t>());
    const std::size_t body = ply.size() - (end + 11);
    ASSERT_EQ(body, 15 * n) << "PLY body truncated or padded";
    for (std::size_t i = 0; i < n; ++i) {
      float xyz[3];
      std::memcpy(xyz, ply.data() + end + 11 + 15 * i, sizeof(xyz));
      ASSERT_TRUE(std::isfinite(xyz[0]) && std::isfinite(xyz[1]) && std::isfinite(xyz[2])) << "vertex " << i;
    }
  }

  static fs::path runner_;
  static fs::path dir_;
};

fs::path RunnerSignal::runner_;
fs::path RunnerSignal::dir_;

}  // namespace

TEST_F(RunnerSignal, SigintWritesTrajectoryMapAndStats) {
  const fs::path out = dir_ / "out_int";
  std::string err;
  const int status = runAndSignal(SIGINT, out, &err);
  ASSERT_TRUE(WIFEXITED(status)) << "killed by signal " << (WIFSIGNALED(status) ? WTERMSIG(status) : 0) << ": " << err;
  EXPECT_EQ(WEXITSTATUS(status), 0) << err;
  EXPECT_EQ(err.find("error"), std::string::npos) << err;
  expectCompleteOutputs(out, err);
}

TEST_F(RunnerSignal, SigtermWritesTrajectoryMapAndStats) {
  const fs::path out = dir_ / "out_term";
  std::string err;
  const int status = runAndSignal(SIGTERM, out, &err);
  ASSERT_TRUE(WIFEXITED(status)) << "killed by signal " << (WIFSIGNALED(status) ? WTERMSIG(status) : 0) << ": " << err;
  EXPECT_EQ(WEXITSTATUS(status), 0) << err;
  expectCompleteOutputs(out, err);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
