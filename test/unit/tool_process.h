#pragma once
// Runs one of the project's command-line tools (built next to the test
// executable) as a user would, and checks the bad-input contract they share:
// exit code 2 and exactly one "error: ..." line on stderr.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace vitamin_e::test {

struct ToolResult {
  int code = -1;
  std::string out, err;
};

inline std::string readText(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// The folder of the running test executable, where CMake also builds the tools.
inline std::filesystem::path testBinaryDir() { return std::filesystem::read_symlink("/proc/self/exe").parent_path(); }

// The tool of that name in the test executable's own folder.
inline std::filesystem::path toolNextToTest(const std::string& name) { return testBinaryDir() / name; }

// `tool args` with no stdin; stdout and stderr pass through files in `dir`.
// timeout_s > 0: killed after that many seconds (a hang fails the test, not the suite).
inline ToolResult runTool(const std::filesystem::path& tool, const std::string& args, const std::filesystem::path& dir,
                          int timeout_s = 0) {
  const std::filesystem::path out = dir / "stdout.txt";
  const std::filesystem::path err = dir / "stderr.txt";
  const std::string limit = timeout_s > 0 ? "timeout " + std::to_string(timeout_s) + " " : "";
  const std::string cmd = limit + tool.string() + " " + args + " </dev/null >" + out.string() + " 2>" + err.string();
  const int status = std::system(cmd.c_str());
  ToolResult r;
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = readText(out);
  r.err = readText(err);
  return r;
}

// Exit code 2 and a single "error: ..." line containing `what`.
inline void expectBadInput(const ToolResult& r, const std::string& args, const std::string& what) {
  EXPECT_EQ(r.code, 2) << args << "\n" << r.err;
  EXPECT_EQ(r.err.rfind("error: ", 0), 0u) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_NE(r.err.find(what), std::string::npos) << "'" << what << "' not in: " << r.err;
}

// A fresh, empty folder for the running test, named after it.
inline std::filesystem::path freshTestDir(const std::string& prefix) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() /
      (prefix + std::to_string(::getpid()) + "_" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

}  // namespace vitamin_e::test
