// The benchmarks (bench/*.cpp, built next to this test) parse their options as
// the command-line tools do (src/apps/cli.h): --help prints the usage and exits
// 0; an unknown option, a missing value or a malformed value is one "error: ..."
// line and exit 2, never an uncaught exception. No data needed: the options are
// checked before anything is read.
#include <gtest/gtest.h>

#include <filesystem>
#include <map>
#include <string>

#include "tool_process.h"

namespace fs = std::filesystem;
using vitamin_e::test::ToolResult;

namespace {

class BenchOptions : public ::testing::Test {
 protected:
  void SetUp() override {
    bin_dir_ = vitamin_e::test::testBinaryDir();
    tmp_ = vitamin_e::test::freshTestDir("ve_bench_opts_");
  }
  void TearDown() override { fs::remove_all(tmp_); }
  ToolResult run(const std::string& bench, const std::string& args) {
    return vitamin_e::test::runTool(bin_dir_ / bench, args, tmp_, 20);
  }
  void expectOneError(const std::string& bench, const std::string& args, const std::string& what) {
    vitamin_e::test::expectBadInput(run(bench, args), bench + " " + args, what);
  }
  fs::path bin_dir_, tmp_;
};

// Per benchmark: an option that takes a number (CMake builds bench/bench_*.cpp into the same folder).
const std::map<std::string, std::string> kNumberOption = {
    {"bench_fusion_dense", "--step"},         {"bench_meshing_delaunay", "--points"},
    {"bench_optimization_ba", "--threads"},   {"bench_optimization_covariance", "--points"},
    {"bench_system_soak", "--minutes"},       {"bench_system_map_file", "--points"},
    {"bench_tracking_render", "--per-frame"}, {"bench_system_step_covariance", "--frames"},
    {"bench_io_png_decode", "--images"},
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
      const ToolResult r = run(bench, help);
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
  expectOneError("bench_io_png_decode", (tmp_ / "none").string(), "not a folder");
  expectOneError("bench_io_png_decode", tmp_.string(), "no .png file");
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
