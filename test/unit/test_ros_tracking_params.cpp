// The tracking nodelet's parameters (tracking_params.h) without a master: defaults, type
// and value errors naming the parameter, the "no IMU" spellings a shell leaves of
// imu_topic:="", old names, docs/ROS.md's table being the one the code generates, and the
// files the parameters name loaded before the nodelet starts (errors name the parameter).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "vitamin_e/ros/tracking_params.h"

using namespace vitamin_e_ros;

namespace {

struct Params {
  std::map<std::string, XmlRpc::XmlRpcValue> values;
  ParamLookup lookup() const {
    return [this](const std::string& name, XmlRpc::XmlRpcValue* v) {
      auto it = values.find(name);
      if (it == values.end()) return false;
      *v = it->second;
      return true;
    };
  }
};

std::string errorOf(const Params& p) {
  try {
    readTrackingParams(p.lookup());
  } catch (const TrackingParamError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(RosTrackingParams, Defaults) {
  const TrackingParams p = readTrackingParams(Params{}.lookup());
  EXPECT_EQ(p.map_frame, "map");
  EXPECT_EQ(p.map_convention, "z_up");
  EXPECT_EQ(p.rectified, "auto");
  EXPECT_EQ(p.image_transport, "raw");
  EXPECT_TRUE(p.imu_topic.empty());
  EXPECT_EQ(p.time_jump, "relocalize");
  EXPECT_EQ(p.subscriberQueue(), 1);
  EXPECT_EQ(p.session().on_time_jump, vitamin_e::pipeline::TimeJumpPolicy::kRelocalize);
  EXPECT_DOUBLE_EQ(p.session().time_jump_threshold_s, 1.0);
}

TEST(RosTrackingParams, ValuesRead) {
  Params in;
  in.values["process_all_frames"] = true;
  in.values["gravity_window"] = 2;  // an integer where a number is expected
  in.values["rectified"] = false;   // a boolean where true/false/auto is expected
  in.values["imu_topic"] = std::string("/imu0");
  in.values["time_jump"] = std::string("drop");
  in.values["load_map"] = std::string("/tmp/x.vemap");
  const TrackingParams p = readTrackingParams(in.lookup());
  EXPECT_TRUE(p.process_all_frames);
  EXPECT_EQ(p.subscriberQueue(), 10000);
  EXPECT_DOUBLE_EQ(p.gravity_window_s, 2.0);
  EXPECT_EQ(p.rectified, "false");
  EXPECT_EQ(p.imu_topic, "/imu0");
  EXPECT_EQ(p.session().on_time_jump, vitamin_e::pipeline::TimeJumpPolicy::kDrop);
  EXPECT_EQ(p.load_map, "/tmp/x.vemap");
}

// What roslaunch and a shell make of imu_topic:="" and its friends: no IMU, never a crash.
TEST(RosTrackingParams, NoImuSpellings) {
  for (const std::string& none : {std::string(""), std::string("\"\""), std::string("''"), std::string("none")}) {
    Params in;
    in.values["imu_topic"] = none;
    ParamNotes notes;
    TrackingParams p;
    ASSERT_NO_THROW(p = readTrackingParams(in.lookup(), &notes)) << none;
    EXPECT_TRUE(p.imu_topic.empty()) << none;
  }
  // The same for any string parameter: a file given as "" is no file.
  Params file;
  file.values["trajectory_file"] = std::string("\"\"");
  EXPECT_TRUE(readTrackingParams(file.lookup()).trajectory_file.empty());
  Params bad;
  bad.values["imu_topic"] = std::string("imu topic");
  EXPECT_NE(errorOf(bad).find("~imu_topic 'imu topic' is not a topic name"), std::string::npos) << errorOf(bad);
}

TEST(RosTrackingParams, ErrorsNameTheParameter) {
  auto expect_error = [](const std::string& name, const XmlRpc::XmlRpcValue& value, const std::string& needle) {
    Params in;
    in.values[name] = value;
    const std::string e = errorOf(in);
    EXPECT_NE(e.find("~" + name), std::string::npos) << name << ": " << e;
    EXPECT_NE(e.find(needle), std::string::npos) << name << ": " << e;
  };
  expect_error("map_convention", std::string("enu"), "z_up, optical");
  expect_error("time_jump", std::string("reset"), "relocalize, drop");
  expect_error("rectified", std::string("maybe"), "true, false, auto");
  expect_error("gravity_window", 0.0, ">= ");
  expect_error("time_jump_threshold", -1.0, ">= ");
  expect_error("debug_frame_delay", 100.0, "[0, 60]");
  expect_error("queue_size", -3, ">= 0");
  expect_error("process_all_frames", std::string("yes"), "true or false");
  expect_error("gravity_window", std::string("1 s"), "a number");
  expect_error("load_map", 3, "a string");
  expect_error("map_frame", std::string(""), "must not be empty");
}

TEST(RosTrackingParams, OldNamesStillRead) {
  Params in;
  in.values["map_file"] = std::string("/tmp/points.ply");
  in.values["reset_on_time_jump"] = false;
  ParamNotes notes;
  const TrackingParams p = readTrackingParams(in.lookup(), &notes);
  EXPECT_EQ(p.export_points, "/tmp/points.ply");
  EXPECT_EQ(p.time_jump, "drop");
  EXPECT_EQ(notes.warnings.size(), 2u);
  // An empty old name (what a launch file passing its default gives) is not worth a warning.
  Params quiet;
  quiet.values["map_file"] = std::string("");
  ParamNotes none;
  readTrackingParams(quiet.lookup(), &none);
  EXPECT_TRUE(none.warnings.empty());
}

// docs/ROS.md holds the table the code generates, between its markers.
TEST(RosTrackingParams, DocIsCurrent) {
  const std::filesystem::path doc = std::filesystem::path(VITAMIN_E_SOURCE_DIR) / "docs" / "ROS.md";
  std::ifstream in(doc);
  ASSERT_TRUE(in.good()) << doc;
  std::stringstream text;
  text << in.rdbuf();
  const std::string s = text.str();
  const std::size_t begin = s.find(kTrackingParamsBegin);
  ASSERT_NE(begin, std::string::npos) << doc << " has no generated parameter table";
  const std::size_t end = s.find(kTrackingParamsEnd, begin);
  ASSERT_NE(end, std::string::npos);
  const std::string in_doc = s.substr(begin, end + std::string(kTrackingParamsEnd).size() + 1 - begin);
  EXPECT_EQ(in_doc, trackingParamsMarkdown())
      << doc << " is stale: regenerate its table with ./scripts/update_ros_docs.sh";
  // Spot checks of the generated rows.
  EXPECT_NE(in_doc.find("| `~imu_topic` |"), std::string::npos);
  EXPECT_NE(in_doc.find("| `~time_jump` | `relocalize` |"), std::string::npos);
}

namespace {
std::string loadError(const TrackingParams& p) {
  try {
    loadTrackingFiles(p);
  } catch (const TrackingParamError& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST(RosTrackingParams, FilesLoadedOrTheParameterNamed) {
  const TrackingFiles none = loadTrackingFiles(TrackingParams{});
  EXPECT_EQ(none.map, nullptr);
  EXPECT_FALSE(none.calibration.has_value());
  EXPECT_EQ(none.system_config.describe(), vitamin_e::pipeline::SystemConfig{}.describe());

  TrackingParams p;
  const std::filesystem::path source(VITAMIN_E_SOURCE_DIR);
  p.config_file = (source / "config" / "euroc.yaml").string();
  p.calibration_file = (source / "config" / "euroc_cam0.yaml").string();
  const TrackingFiles files = loadTrackingFiles(p);
  EXPECT_EQ(files.system_config.describe(), vitamin_e::pipeline::loadSystemConfig(p.config_file).describe());
  ASSERT_TRUE(files.calibration.has_value());
  EXPECT_TRUE(files.calibration.value_or(vitamin_e::camera::CameraCalibration{}).camera.valid());

  TrackingParams missing;
  missing.config_file = "/nonexistent/slam.yaml";
  EXPECT_NE(loadError(missing).find("~config_file '/nonexistent/slam.yaml'"), std::string::npos) << loadError(missing);
  missing = TrackingParams{};
  missing.calibration_file = "/nonexistent/cam.yaml";
  EXPECT_NE(loadError(missing).find("~calibration_file '/nonexistent/cam.yaml'"), std::string::npos)
      << loadError(missing);

  const std::filesystem::path damaged = std::filesystem::temp_directory_path() / "vitamin_e_damaged_map.vemap";
  {
    std::ofstream out(damaged);
    out << "not a map\n";
  }
  TrackingParams bad_map;
  bad_map.load_map = damaged.string();
  EXPECT_NE(loadError(bad_map).find("~load_map: "), std::string::npos) << loadError(bad_map);
  std::filesystem::remove(damaged);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
