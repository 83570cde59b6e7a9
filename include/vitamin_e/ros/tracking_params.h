#pragma once
// The ROS parameters of vitamin_e/TrackingNodelet: one struct, read and validated in
// one function from one table, which also writes the parameter table of docs/ROS.md
// (vitamin_e_ros_params --markdown; test_ros_tracking_params checks the doc is
// current). The SLAM's own settings are in ~config_file (docs/CONFIG.md); the runtime
// ones (publishing, localization only) in cfg/Tracking.cfg (dynamic_reconfigure).
// No master needed: the lookup is a function (the nodelet passes its NodeHandle's).
#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <xmlrpcpp/XmlRpcValue.h>

#include "vitamin_e/camera/camera.h"
#include "vitamin_e/map/map_file.h"
#include "vitamin_e/pipeline/session.h"
#include "vitamin_e/pipeline/system_config.h"

namespace vitamin_e_ros {

struct TrackingParams {
  // Input
  std::string config_file;       // SLAM configuration yaml ("": built-in defaults)
  std::string calibration_file;  // "": from camera_info
  std::string rectified = "auto";
  std::string image_transport = "raw";
  bool process_all_frames = false;
  bool pipelined = false;  // tracking and mapping on two threads (SessionRunner)
  int queue_size = 0;      // 0: 1 live, 10000 with process_all_frames
  // Frames
  std::string map_frame = "map";
  std::string map_convention = "z_up";
  std::string camera_frame;
  std::string base_frame;
  std::string odom_frame;
  std::string body_frame;
  std::string imu_topic;  // "": no IMU
  double gravity_window_s = 1.0;
  // Time
  std::string time_jump = "relocalize";
  double time_jump_threshold_s = 1.0;
  // Files
  std::string trajectory_file;
  std::string export_points;
  std::string load_map;
  std::string save_map;
  // Diagnostics and tests
  double diagnostic_period_s = 1.0;
  double debug_frame_delay_s = 0.0;
  // Process
  bool reuse_freed_memory = true;  // vitamin_e::reuseFreedFrameBuffers() at start-up

  bool opticalMap() const { return map_convention == "optical"; }
  // The image subscriber's queue.
  int subscriberQueue() const { return queue_size > 0 ? queue_size : (process_all_frames ? 10000 : 1); }
  vitamin_e::pipeline::SessionConfig session() const;
};

// A parameter's value is wrong: what() names it and says what is accepted.
class TrackingParamError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

// name (without "~") -> its value, false when the parameter is not set.
using ParamLookup = std::function<bool(const std::string& name, XmlRpc::XmlRpcValue* value)>;

// What reading said besides the values: old names used, values normalized.
struct ParamNotes {
  std::vector<std::string> warnings;
  std::vector<std::string> infos;
};

// Reads every parameter of the table (unset: the default), then checks them together.
// Throws TrackingParamError naming the first bad one. "", '' and none for ~imu_topic
// (what a shell leaves of imu_topic:="") mean no IMU.
TrackingParams readTrackingParams(const ParamLookup& lookup, ParamNotes* notes = nullptr);

// What the parameters' files hold, loaded and checked before the nodelet starts anything.
struct TrackingFiles {
  vitamin_e::pipeline::SystemConfig system_config;                  // ~config_file, else the defaults; validated
  std::unique_ptr<vitamin_e::map::MapFileContents> map;             // ~load_map; null: none
  std::optional<vitamin_e::camera::CameraCalibration> calibration;  // ~calibration_file; none: from camera_info
};

// Loads ~config_file, ~load_map and ~calibration_file. Throws TrackingParamError naming the
// parameter, the file and what is wrong with it.
TrackingFiles loadTrackingFiles(const TrackingParams& params);

// The parameter table of docs/ROS.md (markdown, one row per parameter, in table order).
std::string trackingParamsMarkdown();
// The markers around it in docs/ROS.md.
extern const char* const kTrackingParamsBegin;
extern const char* const kTrackingParamsEnd;

}  // namespace vitamin_e_ros
