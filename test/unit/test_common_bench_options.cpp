// The benchmarks (bench/*.cpp, built next to this test) parse their options as
// the command-line tools do (src/apps/cli.h): --help prints the usage and exits
// 0; an unknown option, a missing value or a malformed value is one "error: ..."
// line and exit 2, never an uncaught exception. No data needed: the options are
// checked before anything is read.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>

namespace fs = std::filesystem;

namespace {

struct Result {
  int code = -1;
  std::string out, err;
};

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

class BenchOptions : public ::testing::Test {
 protected:
  void SetUp() override {
    bin_dir_ = fs::read_symlink("/proc/self/exe").parent_path();
    tmp_ = fs::temp_directory_path() / ("ve_bench_opts_" + std::to_string(::getpid()));
    fs::create_directories(tmp_);
  }
  void TearDown() override { fs::remove_all(tmp_); }
  Result run(const std::string& bench, const std::string& args) {
    const fs::path out = tmp_ / "out.txt", err = tmp_ / "err.txt";
    const std::string cmd = "timeout 20 " + (bin_dir_ / bench).string() + " " + args + " </dev/null >" + out.string() +
                            " 2>" + err.string();
    const int status = std::system(cmd.c_str());
    Result r;
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.out = slurp(out);
    r.err = slurp(err);
    return r;
  }
  void expectOneError(const std::string& bench, const std::string& args, const std::string& what) {
    const Result r = run(bench, args);
    EXPECT_EQ(r.code, 2) << bench << " " << args << "\n" << r.err;
    EXPECT_EQ(r.err.rfind("error: ", 0), 0u) << bench << " " << args << ": " << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << bench << " " << args << ": " << r.err;
    EXPECT_NE(r.err.find(what), std::string::npos) << bench << " " << args << ": '" << what << "' not in " << r.err;
  }
  fs::path bin_dir_, tmp_;
};

// Per benchmark: an option that takes a number (CMake builds bench/bench_*.cpp into the same folder).
const std::map<std::string, std::string> kNumberOption = {
    {"bench_fusion_dense", "--step"},         {"bench_meshing_delaunay", "--points"},
    {"bench_optimization_ba", "--threads"},   {"bench_optimization_covariance", "--points"},
    {"bench_system_soak", "--minutes"},       {"bench_system_map_file", "--points"},
    {"bench_tracking_render", "--per-frame"}, {"bench_system_step_covariance", "--frames"},
};

}  // namespace

TEST_F(BenchOptions, EveryBenchmarkIsCovered) {
  std::size_t found = 0;
  for (const auto& entry : fs::directory_iterator(bin_dir_)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("bench_", 0) != 0) continue;
    ++found;
    EXPECT_TRUE(kNumberOption.count(name)) << name << ": add it to kNumberOption of this test";
  }
  for (const auto& [bench, option] : kNumberOption) {
    EXPECT_TRUE(fs::exists(bin_dir_ / bench)) << bench << " not built in " << bin_dir_;
  }
  EXPECT_EQ(found, kNumberOption.size());
}

TEST_F(BenchOptions, HelpPrintsTheUsageAndExitsZero) {
  for (const auto& [bench, option] : kNumberOption) {
    for (const char* help : {"--help", "-h"}) {
      const Result r = run(bench, help);
      EXPECT_EQ(r.code, 0) << bench << " " << help << "\n" << r.err;
      EXPECT_EQ(r.out.rfind("usage: " + bench, 0), 0u) << bench << ": " << r.out;
      EXPECT_NE(r.out.find(option), std::string::npos) << bench << " usage does not list " << option;
      EXPECT_EQ(r.err, "") << bench;
    }
    // --help wins wherever it stands, also after a bad option.
    EXPECT_EQ(run(bench, "--bogus --help").code, 0) << bench;
  }
}

TEST_F(BenchOptions, BadOptionsAreOneErrorLineAndExitTwo) {
  for (const auto& [bench, option] : kNumberOption) {
    expectOneError(bench, "--bogus-option", "unknown option '--bogus-option'");
    expectOneError(bench, option, option + " needs a value");
    expectOneError(bench, option + " many", option);
    expectOneError(bench, option + " 3x", option);
  }
  // Values out of range, and a render that is not one.
  expectOneError("bench_tracking_render", (tmp_ / "none").string(), "not a render");
  expectOneError("bench_tracking_render", "--frames 1", "RENDER_DIR");
  expectOneError("bench_fusion_dense", (tmp_ / "none").string(), "not found");
  expectOneError("bench_optimization_ba", "--threads 0", "--threads");
  expectOneError("bench_system_soak", "--width 10", "--width");
  expectOneError("bench_meshing_delaunay", "--repeats 0", "--repeats");
  expectOneError("bench_system_map_file", "--repeat 0", "--repeat");
  expectOneError("bench_system_map_file", "--map " + (tmp_ / "none.vemap").string(), "none.vemap");
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
