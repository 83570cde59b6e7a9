// vitamin_e_ros_params: the tracking nodelet's ROS parameters (src/ros/tracking_params.cpp)
// without ROS running.
//   vitamin_e_ros_params --markdown        the parameter table of docs/ROS.md
//   vitamin_e_ros_params --check FILE.yaml  reads a parameter file (e.g. config/ros_tracking.yaml)
//                                           as the nodelet would: "ok" or the first bad value
// Bad arguments or a bad file: one "error: ..." line, exit 2.
#include <iostream>
#include <string>

#include <yaml-cpp/yaml.h>

#include "cli.h"

#if VITAMIN_E_WITH_ROS
#include "vitamin_e/ros/tracking_params.h"
#endif

namespace {

constexpr const char* kUsage = "usage: vitamin_e_ros_params --markdown | --check FILE.yaml\n"
                               "  --markdown    print the tracking nodelet's parameter table (docs/ROS.md)\n"
                               "  --check FILE  read a yaml of the nodelet's private parameters and validate them\n";

#if VITAMIN_E_WITH_ROS
// A yaml scalar as the parameter server would hold it (rosparam's typing).
XmlRpc::XmlRpcValue toValue(const YAML::Node& n) {
  const std::string& s = n.Scalar();
  if (n.Tag() != "!" && (s == "true" || s == "false")) return XmlRpc::XmlRpcValue(s == "true");
  if (n.Tag() != "!") {
    char* end = nullptr;
    const long long i = std::strtoll(s.c_str(), &end, 10);
    if (!s.empty() && *end == '\0') return XmlRpc::XmlRpcValue(static_cast<int>(i));
    const double d = std::strtod(s.c_str(), &end);
    if (!s.empty() && *end == '\0') return XmlRpc::XmlRpcValue(d);
  }
  return XmlRpc::XmlRpcValue(s);
}

int check(const std::string& path) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const std::exception& e) {
    vitamin_e::cli::fail(path + ": " + e.what());
  }
  if (root && !root.IsNull() && !root.IsMap()) vitamin_e::cli::fail(path + ": expected a map of parameters");
  auto lookup = [&root](const std::string& name, XmlRpc::XmlRpcValue* value) {
    if (!root || root.IsNull() || !root[name] || !root[name].IsScalar()) return false;
    *value = toValue(root[name]);
    return true;
  };
  vitamin_e_ros::ParamNotes notes;
  try {
    vitamin_e_ros::readTrackingParams(lookup, &notes);
  } catch (const std::exception& e) {
    vitamin_e::cli::fail(path + ": " + e.what());
  }
  for (const auto& w : notes.warnings) std::cout << "warning: " << w << "\n";
  std::cout << "ok\n";
  return 0;
}
#endif

int run(int argc, char** argv) {
  const std::string a = argc > 1 ? argv[1] : "";
  if (a == "-h" || a == "--help") {
    std::cout << kUsage;
    return 0;
  }
#if VITAMIN_E_WITH_ROS
  if (a == "--markdown" && argc == 2) {
    std::cout << vitamin_e_ros::trackingParamsMarkdown();
    return 0;
  }
  if (a == "--check" && argc == 3) return check(argv[2]);
#else
  vitamin_e::cli::fail("built without the ROS layer");
#endif
  std::cerr << kUsage;
  vitamin_e::cli::fail("expected --markdown or --check FILE.yaml");
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {  // a bad_alloc, a stream error: said, never an abort
    vitamin_e::cli::fail(e.what());
  }
}
