// The command-line tools vitamin_e_evaluate and vitamin_e_make_sequence (built
// next to this test) on good and bad arguments: bad input gives exactly one
// "error: ..." line and exit code 2; good input reaches the computation.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include <yaml-cpp/yaml.h>

#include "tool_process.h"

namespace fs = std::filesystem;

namespace {

using Result = vitamin_e::test::ToolResult;

class ToolTest : public ::testing::Test {
 protected:
  void SetUp() override {
    evaluate_ = vitamin_e::test::toolNextToTest("vitamin_e_evaluate");
    make_sequence_ = vitamin_e::test::toolNextToTest("vitamin_e_make_sequence");
    // A missing tool is a failure, never a skip: a skipped test would let CI pass untested.
    ASSERT_TRUE(fs::exists(evaluate_)) << "vitamin_e_evaluate not built (" << evaluate_ << ")";
    ASSERT_TRUE(fs::exists(make_sequence_)) << "vitamin_e_make_sequence not built (" << make_sequence_ << ")";
    dir_ = vitamin_e::test::freshTestDir("ve_tools_");
  }
  void TearDown() override {
    if (!dir_.empty()) fs::remove_all(dir_);
  }
  Result run(const fs::path& tool, const std::string& args) { return vitamin_e::test::runTool(tool, args, dir_); }
  void expectBadInput(const fs::path& tool, const std::string& args, const std::string& what) {
    vitamin_e::test::expectBadInput(run(tool, args), args, what);
  }
  // A TUM trajectory along a curve: scale s and offset (dx, 0, 0) of the same path.
  fs::path writeTrajectory(const std::string& name, double s, double dx) const {
    const fs::path p = dir_ / name;
    std::ofstream f(p);
    for (int i = 0; i < 50; ++i) {
      const double t = 0.1 * i;
      char line[200];
      std::snprintf(line, sizeof(line), "%.3f %.6f %.6f %.6f 0 0 0 1\n", t, s * std::sin(t) + dx, s * 0.5 * t,
                    s * 0.1 * t * t);
      f << line;
    }
    return p;
  }
  fs::path evaluate_, make_sequence_;
  fs::path dir_;
};

TEST_F(ToolTest, EvaluateTakesTheTwoTrajectoriesInAnyOrderOfOptions) {
  const fs::path gt = writeTrajectory("gt.txt", 1.0, 0.0);
  const fs::path est = writeTrajectory("est.txt", 2.0, 3.0);  // the same path at twice the scale, moved
  Result r = run(evaluate_, "--json " + est.string() + " " + gt.string());
  ASSERT_EQ(r.code, 0) << r.err;
  YAML::Node j = YAML::Load(r.out);
  EXPECT_LT(j["ate_rmse_m"].as<double>(), 1e-6) << r.out;  // Sim(3) removes scale and offset
  EXPECT_EQ(j["matched"].as<int>(), 50);
  // --se3 (scale known) after the positionals: the scale is no longer removed.
  r = run(evaluate_, est.string() + " " + gt.string() + " --se3 --json");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_GT(YAML::Load(r.out)["ate_rmse_m"].as<double>(), 0.1) << r.out;
  // --frames counts the input frames for the success rate.
  r = run(evaluate_, "--frames 100 --json " + est.string() + " " + gt.string());
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NEAR(YAML::Load(r.out)["success_rate"].as<double>(), 0.5, 1e-9) << r.out;
  // --errors-out writes one line per matched pose.
  const fs::path errors = dir_ / "errors.txt";
  r = run(evaluate_, est.string() + " " + gt.string() + " --errors-out " + errors.string());
  ASSERT_EQ(r.code, 0) << r.err;
  std::ifstream lines(errors);
  int poses = 0;
  for (std::string line; std::getline(lines, line);) poses += !line.empty() && line[0] != '#';
  EXPECT_EQ(poses, 50);
}

TEST_F(ToolTest, EvaluateBadArgumentsExitWithCode2) {
  const std::string gt = writeTrajectory("gt.txt", 1.0, 0.0).string();
  expectBadInput(evaluate_, "", "expected TRAJ and GT");
  expectBadInput(evaluate_, gt, "expected TRAJ and GT");
  expectBadInput(evaluate_, gt + " " + gt + " " + gt, "unexpected argument");
  expectBadInput(evaluate_, gt + " " + gt + " --bogus", "unknown option '--bogus'");
  expectBadInput(evaluate_, gt + " " + gt + " --frames -2", "--frames");
  expectBadInput(evaluate_, gt + " " + gt + " --max-dt abc", "--max-dt");
  expectBadInput(evaluate_, gt + " " + gt + " --rpe-delta", "--rpe-delta needs a value");
  expectBadInput(evaluate_, gt + " " + gt + " --alignment-gt " + gt, "--alignment-gt needs --alignment-from");
  expectBadInput(evaluate_, (dir_ / "none.txt").string() + " " + gt, "none.txt");
  const Result help = run(evaluate_, gt + " --help");
  EXPECT_EQ(help.code, 0);
  EXPECT_EQ(help.out.rfind("usage: vitamin_e_evaluate", 0), 0u) << help.out;
}

TEST_F(ToolTest, MakeSequenceBadArgumentsExitWithCode2) {
  const std::string out = " --out " + (dir_ / "seq").string();
  expectBadInput(make_sequence_, "--frames 3", "--out DIR is required");
  expectBadInput(make_sequence_, "--scene moon" + out, "--scene must be room or street");
  expectBadInput(make_sequence_, "--path long" + out, "--path applies to --scene street only");
  expectBadInput(make_sequence_, "--scene street --boxes 3" + out, "--boxes applies to the room scene only");
  expectBadInput(make_sequence_, "--scene street --speed 1" + out, "--speed applies to the room scene only");
  expectBadInput(make_sequence_, "--scene street --distortion euroc" + out, "applies to the room scene only");
  expectBadInput(make_sequence_, "--distortion fisheye" + out, "--distortion must be euroc or none");
  expectBadInput(make_sequence_, "--seed -1" + out, "--seed");
  expectBadInput(make_sequence_, "--width 1.5" + out, "--width");
  expectBadInput(make_sequence_, "--bogus 1" + out, "unknown option '--bogus'");
  EXPECT_FALSE(fs::exists(dir_ / "seq"));
  // --help wins over anything else on the line, a bad scene included.
  const Result help = run(make_sequence_, "--scene moon --help");
  EXPECT_EQ(help.code, 0) << help.err;
  EXPECT_NE(help.out.find("vitamin_e_make_sequence"), std::string::npos) << help.out;
}

TEST_F(ToolTest, MakeSequenceWritesTheFramesAsked) {
  const fs::path seq = dir_ / "seq";
  const Result r = run(make_sequence_, "--frames 3 --width 96 --height 64 --seed 2 --out " + seq.string());
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("wrote 3 frames (96x64, 20.0 Hz, seed 2, euroc distortion)"), std::string::npos) << r.out;
  int pngs = 0;
  for (const auto& e : fs::recursive_directory_iterator(seq)) pngs += e.path().extension() == ".png";
  EXPECT_EQ(pngs, 3);
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
