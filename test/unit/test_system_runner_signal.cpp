// The offline runner (vitamin_e_run, built next to this test) stopped by SIGINT
// or SIGTERM in the middle of a run on a generated sequence: it must finish the
// current frame, write trajectory.txt, points.ply and stats.json (well-formed,
// finite, marked interrupted) and exit 0, within seconds (no hang). The map and
// TSDF files asked for are written too, and a later run localizes in that map
// (--load-map --localization-only) without initializing; damaged map files give
// one error line and exit code 2.
#include <gtest/gtest.h>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <thread>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "vitamin_e/map/map_file.h"
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
    runner_path = fs::read_symlink("/proc/self/exe").parent_path() / "vitamin_e_run";
    work_dir = fs::temp_directory_path() / ("ve_runner_signal_" + std::to_string(::getpid()));
    fs::remove_all(work_dir);
    if (!fs::exists(runner_path)) return;
    vitamin_e::synth::SequenceConfig seq;
    seq.frames = kRendered;
    seq.width = 376;
    seq.height = 240;
    seq.seed = 2;
    vitamin_e::synth::writeSequence((work_dir / "seq").string(), seq);
    // The images listed back and forth (0..39, 38..1, 0..) with increasing stamps:
    // a long, continuous sequence from a few rendered frames.
    const fs::path cam = work_dir / "seq" / "mav0" / "cam0";
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
  static void TearDownTestSuite() { fs::remove_all(work_dir); }

  void SetUp() override {
    ASSERT_TRUE(fs::exists(runner_path)) << "vitamin_e_run not built (" << runner_path << ")";  // a failure, not a skip
    ASSERT_TRUE(fs::exists(work_dir / "seq" / "mav0" / "cam0" / "data.csv"));
  }

  // Starts the runner, waits until it has processed a few frames, sends `sig`,
  // and waits (at most 60 s) for it to exit. Returns the exit status.
  int runAndSignal(int sig, const fs::path& out, std::string* err, const std::vector<std::string>& extra = {}) {
    const fs::path err_path = out.string() + ".stderr";
    const pid_t pid = ::fork();
    if (pid == 0) {
      std::freopen("/dev/null", "r", stdin);
      std::freopen("/dev/null", "w", stdout);
      std::freopen(err_path.c_str(), "w", stderr);
      const std::string dataset = (work_dir / "seq").string(), out_dir = out.string(), runner = runner_path.string();
      std::vector<const char*> argv = {runner.c_str(), "--dataset", dataset.c_str(), "--out", out_dir.c_str()};
      for (const std::string& a : extra) argv.push_back(a.c_str());
      argv.push_back(nullptr);
      ::execv(runner.c_str(), const_cast<char* const*>(argv.data()));
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

  static fs::path runner_path;
  static fs::path work_dir;
};

fs::path RunnerSignal::runner_path;
fs::path RunnerSignal::work_dir;

}  // namespace

TEST_F(RunnerSignal, SigintWritesTrajectoryMapAndStats) {
  const fs::path out = work_dir / "out_int";
  std::string err;
  const int status = runAndSignal(SIGINT, out, &err);
  ASSERT_TRUE(WIFEXITED(status)) << "killed by signal " << (WIFSIGNALED(status) ? WTERMSIG(status) : 0) << ": " << err;
  EXPECT_EQ(WEXITSTATUS(status), 0) << err;
  EXPECT_EQ(err.find("error"), std::string::npos) << err;
  expectCompleteOutputs(out, err);
}

TEST_F(RunnerSignal, SigtermWritesTrajectoryMapAndStats) {
  const fs::path out = work_dir / "out_term";
  std::string err;
  const int status = runAndSignal(SIGTERM, out, &err);
  ASSERT_TRUE(WIFEXITED(status)) << "killed by signal " << (WIFSIGNALED(status) ? WTERMSIG(status) : 0) << ": " << err;
  EXPECT_EQ(WEXITSTATUS(status), 0) << err;
  expectCompleteOutputs(out, err);
}

namespace {
// Runs the runner to the end; returns its exit code and stderr.
int runToEnd(const fs::path& runner, const std::string& args, const fs::path& err_path, std::string* err) {
  const std::string cmd = runner.string() + " " + args + " </dev/null >/dev/null 2>" + err_path.string();
  const int status = std::system(cmd.c_str());
  *err = readFile(err_path);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}
}  // namespace

TEST_F(RunnerSignal, SigintWritesTheMapAndALaterRunLocalizesInIt) {
  const fs::path out = work_dir / "out_map";
  const std::string map = (work_dir / "seq.vemap").string(), tsdf = (work_dir / "seq.vetsdf").string();
  std::string err;
  const int status = runAndSignal(SIGINT, out, &err, {"--save-map", map, "--save-tsdf", tsdf});
  ASSERT_TRUE(WIFEXITED(status)) << err;
  ASSERT_EQ(WEXITSTATUS(status), 0) << err;
  const vitamin_e::map::MapFileContents saved = vitamin_e::map::loadMapFile(map);
  EXPECT_EQ(readFile(map).rfind("vitamin_e map v1, ", 0), 0u);
  EXPECT_EQ(saved.camera.width(), 376);
  ASSERT_GT(saved.keyframe_index.size(), 0u) << "the interrupted run made no keyframe: " << err;
  const std::string map_bytes = readFile(map);

  // Frames 0..59 of the same sequence in the saved map: found by the
  // relocalizer, no initialization, the file untouched.
  const fs::path out2 = work_dir / "out_localize";
  const std::string base = "--dataset " + (work_dir / "seq").string() + " --max-frames 60 --quiet";
  ASSERT_EQ(runToEnd(runner_path,
                     base + " --out " + out2.string() + " --load-map " + map + " --localization-only" +
                         " --load-tsdf " + tsdf,
                     work_dir / "localize.stderr", &err),
            0)
      << err;
  const YAML::Node stats = YAML::LoadFile((out2 / "stats.json").string());
  EXPECT_EQ(stats["init_retries"].as<int>(), 0);
  EXPECT_EQ(stats["first_init_frame"].as<int>(), -1);
  EXPECT_GE(stats["relocalizations"].as<int>(), 1);
  EXPECT_GE(stats["tracked_frames"].as<int>(), 50) << err;
  EXPECT_TRUE(readFile(map) == map_bytes);

  // Bad map files: one error line, exit code 2.
  auto expect_refused = [&](const std::string& args, const std::string& what) {
    const int code = runToEnd(runner_path, base + " --out " + (work_dir / "out_bad").string() + " " + args,
                              work_dir / "bad.stderr", &err);
    EXPECT_EQ(code, 2) << args << ": " << err;
    EXPECT_EQ(err.rfind("error: ", 0), 0u) << err;
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
    EXPECT_NE(err.find(what), std::string::npos) << "'" << what << "' not in: " << err;
  };
  const std::string empty = (work_dir / "empty.vemap").string(), cut = (work_dir / "cut.vemap").string(),
                    flipped = (work_dir / "flipped.vemap").string(), other = (work_dir / "other.vemap").string();
  std::ofstream(empty, std::ios::binary).flush();
  std::ofstream(cut, std::ios::binary) << map_bytes.substr(0, map_bytes.size() * 2 / 3);
  std::string flip = map_bytes;
  flip[flip.size() / 2] = static_cast<char>(flip[flip.size() / 2] ^ 0x10);
  std::ofstream(flipped, std::ios::binary) << flip;
  vitamin_e::map::MapFileContents small = saved;
  small.camera = vitamin_e::camera::Camera(188, 120, 100.0, 100.0, 94.0, 60.0);
  ASSERT_TRUE(vitamin_e::map::saveMapFile(small, other));
  expect_refused("--load-map " + (work_dir / "missing.vemap").string(), "missing.vemap");
  expect_refused("--load-map " + empty, "empty");
  expect_refused("--load-map " + cut, "truncated");
  expect_refused("--load-map " + flipped, "corrupt");
  expect_refused("--load-map " + other, "188x120");
  expect_refused("--localization-only", "--load-map");
  expect_refused("--load-map " + map + " --localization-only --save-map " + map, "--save-map");
  expect_refused("--load-tsdf " + map, "not a vitamin_e TSDF file");
  EXPECT_TRUE(readFile(map) == map_bytes);
}

namespace {
// The integer after "key=" in a --log-frames line (-1 when absent).
long tokenValue(const std::string& line, const std::string& key) {
  const std::size_t at = line.find(" " + key + "=");
  return at == std::string::npos ? -1 : std::stol(line.substr(at + key.size() + 2));
}
}  // namespace

// --log-frames prints the frame's counters (FrameDiagnostics) on every line and
// stats.json summarizes them: the tracks balance from line to line, and the
// sums in stats.json are those of the lines.
TEST_F(RunnerSignal, LogFramesAndStatsCarryTheCounters) {
  const fs::path out = work_dir / "out_counters";
  const fs::path log = work_dir / "counters.log";
  const std::string cmd = runner_path.string() + " --dataset " + (work_dir / "seq").string() +
                          " --max-frames 30 --quiet" + " --log-frames --out " + out.string() + " </dev/null >" +
                          log.string() + " 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << readFile(log);
  std::istringstream lines(readFile(log));
  long born = 0, lost = 0, dropped = 0, triangulated = 0, keyframes = 0, prev_tracks = -1;
  int n = 0, with_prev_map = 0;
  for (std::string line; std::getline(lines, line);) {
    std::istringstream ls(line);
    long index = 0, tracks = 0, mapped = 0;
    double stamp = 0.0, ms = 0.0;
    std::string state;
    ASSERT_TRUE(static_cast<bool>(ls >> index >> stamp >> state >> tracks >> mapped >> ms)) << line;
    EXPECT_EQ(index, n) << line;
    for (const char* key :
         {"born", "lost", "dropped", "prev_map", "pose", "reuse", "kf", "kf_par", "tri", "cand", "cand_par", "kfs"}) {
      EXPECT_GE(tokenValue(line, key), 0) << key << " missing: " << line;
    }
    const long b = tokenValue(line, "born"), l = tokenValue(line, "lost"), d = tokenValue(line, "dropped");
    if (prev_tracks >= 0) {
      EXPECT_EQ(prev_tracks, tracks - b + l + d) << line;
    }
    prev_tracks = tracks;
    born += b;
    lost += l;
    dropped += d;
    triangulated += tokenValue(line, "tri");
    keyframes += tokenValue(line, "kf");
    with_prev_map += tokenValue(line, "prev_map") > 0 ? 1 : 0;
    ++n;
  }
  ASSERT_EQ(n, 30) << readFile(log);
  EXPECT_GT(triangulated, 100);
  EXPECT_GE(keyframes, 2);
  EXPECT_GT(with_prev_map, 10);
  const YAML::Node fd = YAML::LoadFile((out / "stats.json").string())["frame_diagnostics"];
  ASSERT_TRUE(fd.IsMap());
  EXPECT_EQ(fd["tracks_born"]["sum"].as<long>(), born);
  EXPECT_EQ(fd["tracks_lost"]["sum"].as<long>(), lost);
  EXPECT_EQ(fd["tracks_dropped"]["sum"].as<long>(), dropped);
  EXPECT_EQ(fd["triangulated"]["sum"].as<long>(), triangulated);
  EXPECT_EQ(fd["keyframe"]["sum"].as<long>(), keyframes);
  for (const char* key :
       {"prev_map_tracked_fraction", "mapped_tracks", "candidates", "candidate_parallax_deg", "pose_inliers"}) {
    ASSERT_TRUE(fd[key].IsMap()) << key;
    EXPECT_GE(fd[key]["max"].as<double>(), fd[key]["median"].as<double>()) << key;
  }
  EXPECT_LE(fd["prev_map_tracked_fraction"]["max"].as<double>(), 1.0);
  EXPECT_GT(fd["prev_map_tracked_fraction"]["median"].as<double>(), 0.5);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
