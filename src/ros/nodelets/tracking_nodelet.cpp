#include "tracking_nodelet.h"

#include <chrono>
#include <cstdio>
#include <exception>

#include <pluginlib/class_list_macros.hpp>

#include <geometry_msgs/PoseStamped.h>
#include <nav_msgs/Odometry.h>
#include <sensor_msgs/PointCloud2.h>

#include "vitamin_e/TrackedFrame.h"
#include "vitamin_e/TrackingStatus.h"
#include "vitamin_e/ros/conversions.h"

namespace vitamin_e_ros {

using vitamin_e::pipeline::FrameResult;

void TrackingNodelet::onInit() {
  ros::NodeHandle& nh = getNodeHandle();
  ros::NodeHandle& pnh = getPrivateNodeHandle();

  pnh.param<std::string>("map_frame", map_frame_, "map");
  pnh.param<std::string>("camera_frame", camera_frame_, "");
  pnh.param<std::string>("odom_frame", odom_frame_, "");
  pnh.param<std::string>("base_frame", base_frame_, "");
  pnh.param<std::string>("trajectory_file", trajectory_file_, "");
  pnh.param<std::string>("export_points", export_points_, "");
  std::string legacy_points_file;
  if (pnh.getParam("map_file", legacy_points_file) && export_points_.empty()) {
    export_points_ = legacy_points_file;
    NODELET_WARN("~map_file is the PLY export of the map points, now called ~export_points (~save_map: the map file)");
  }
  pnh.param<std::string>("load_map", load_map_, "");
  pnh.param<std::string>("save_map", save_map_, "");
  pnh.param("process_all_frames", process_all_frames_, false);
  int queue_size = 1;
  pnh.param("queue_size", queue_size, process_all_frames_ ? 10000 : 1);
  std::string config_file, calibration_file;
  pnh.param<std::string>("config_file", config_file, "");
  pnh.param<std::string>("calibration_file", calibration_file, "");

  try {
    if (!config_file.empty()) {
      system_config_ = vitamin_e::pipeline::loadSystemConfig(config_file);
    }
    system_config_.validate();
  } catch (const std::exception& e) {
    NODELET_FATAL("~config_file '%s': %s (no subscription: fix the config and restart)", config_file.c_str(),
                  e.what());
    return;
  }
  NODELET_INFO("SLAM config %s:\n%s", config_file.empty() ? "(defaults)" : config_file.c_str(),
               system_config_.describe().c_str());
  if (!load_map_.empty()) {
    try {
      loaded_map_ = std::make_unique<vitamin_e::map::MapFileContents>(vitamin_e::map::loadMapFile(load_map_));
    } catch (const std::exception& e) {
      NODELET_FATAL("~load_map: %s (no subscription: fix the file or the parameter and restart)", e.what());
      return;
    }
    NODELET_INFO("~load_map %s: %s", load_map_.c_str(), vitamin_e::map::mapFileHeader(*loaded_map_).c_str());
  }

  path_.header.frame_id = map_frame_;
  pose_pub_ = pnh.advertise<geometry_msgs::PoseStamped>("pose", 10);
  odom_pub_ = pnh.advertise<nav_msgs::Odometry>("odometry", 10);
  path_pub_ = pnh.advertise<nav_msgs::Path>("path", 1, true);
  points_pub_ = pnh.advertise<sensor_msgs::PointCloud2>("points", 2);
  map_points_pub_ = pnh.advertise<sensor_msgs::PointCloud2>("map_points", 1, true);
  status_pub_ = pnh.advertise<vitamin_e::TrackingStatus>("status", 10);
  frame_pub_ = pnh.advertise<vitamin_e::TrackedFrame>("frame", process_all_frames_ ? 1000 : 5);
  it_ = std::make_unique<image_transport::ImageTransport>(nh);
  image_transport::ImageTransport private_it(pnh);
  tracking_image_pub_ = private_it.advertise("tracking_image", 1);

  tf_broadcaster_ = std::make_unique<tf2_ros::TransformBroadcaster>();
  if (!odom_frame_.empty() && !base_frame_.empty()) {
    tf_buffer_ = std::make_unique<tf2_ros::Buffer>();
    tf_listener_ = std::make_unique<tf2_ros::TransformListener>(*tf_buffer_, nh);
    NODELET_INFO("REP-105: publishing %s -> %s (from %s -> %s)", map_frame_.c_str(), odom_frame_.c_str(),
                 odom_frame_.c_str(), base_frame_.c_str());
  }

  reconfigure_server_ =
      std::make_unique<dynamic_reconfigure::Server<vitamin_e::TrackingConfig>>(reconfigure_mutex_, pnh);
  reconfigure_server_->setCallback(
      [this](vitamin_e::TrackingConfig& c, uint32_t level) { reconfigure(c, level); });

  reset_srv_ = pnh.advertiseService("reset", &TrackingNodelet::resetService, this);
  save_trajectory_srv_ = pnh.advertiseService("save_trajectory", &TrackingNodelet::saveTrajectoryService, this);
  save_map_srv_ = pnh.advertiseService("save_map", &TrackingNodelet::saveMapService, this);
  export_points_srv_ = pnh.advertiseService("export_points", &TrackingNodelet::exportPointsService, this);

  if (!calibration_file.empty()) {
    try {
      const auto calibration = vitamin_e::camera::loadCalibration(calibration_file);
      if (!createSystem(calibration.camera)) return;
    } catch (const std::exception& e) {
      NODELET_FATAL("~calibration_file '%s': %s", calibration_file.c_str(), e.what());
      return;
    }
  } else {
    info_sub_ = nh.subscribe("camera_info", 1, &TrackingNodelet::cameraInfoCallback, this);
    NODELET_INFO("no ~calibration_file: waiting for %s", info_sub_.getTopic().c_str());
  }
  image_sub_ = it_->subscribe("image", static_cast<uint32_t>(std::max(1, queue_size)),
                              &TrackingNodelet::imageCallback, this);
  NODELET_INFO("subscribed to %s (queue %d, %s)", image_sub_.getTopic().c_str(), queue_size,
               process_all_frames_ ? "every frame processed" : "live: stale frames dropped");
}

bool TrackingNodelet::createSystem(const vitamin_e::camera::Camera& camera) {
  try {
    system_ = std::make_unique<vitamin_e::pipeline::System>(system_config_, camera);
  } catch (const std::exception& e) {
    NODELET_FATAL("cannot start the SLAM system: %s", e.what());
    return false;
  }
  NODELET_INFO("camera: %s", camera.describe().c_str());
  if (loaded_map_) {
    try {
      system_->loadMap(*loaded_map_);
    } catch (const std::exception& e) {
      NODELET_FATAL("~load_map '%s': %s (no subscription: fix the file or the parameter and restart)",
                    load_map_.c_str(), e.what());
      system_.reset();
      image_sub_.shutdown();
      info_sub_.shutdown();
      return false;
    }
    loaded_map_.reset();
    NODELET_INFO("relocalizing in the loaded map %s%s", load_map_.c_str(),
                 dyn_.localization_only ? " (localization only)" : "");
  }
  system_->setLocalizationOnly(dyn_.localization_only);
  return true;
}

TrackingNodelet::~TrackingNodelet() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (system_) {  // stderr: rosout may be gone at shutdown
    std::fprintf(stderr, "[vitamin_e] %zu frames processed, %zu tracked, %d init retries\n%s",
                 system_->framesProcessed(), system_->framesTracked(), system_->initRetries(),
                 system_->timings().table().c_str());
  }
  std::string message;
  if (system_ && !trajectory_file_.empty()) {
    saveTrajectory(trajectory_file_, &message);
    std::fprintf(stderr, "[vitamin_e] %s\n", message.c_str());
  }
  if (system_ && !export_points_.empty()) {
    exportPoints(export_points_, &message);
    std::fprintf(stderr, "[vitamin_e] %s\n", message.c_str());
  }
  if (system_ && !save_map_.empty()) {
    if (system_->localizationOnly()) {
      message = "localization only: the map is unchanged, " + save_map_ + " not written";
    } else {
      saveMap(save_map_, &message);
    }
    std::fprintf(stderr, "[vitamin_e] %s\n", message.c_str());
  }
}

void TrackingNodelet::cameraInfoCallback(const sensor_msgs::CameraInfoConstPtr& msg) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (system_) {
    info_sub_.shutdown();
    return;
  }
  try {
    if (createSystem(cameraFromInfo(*msg))) info_sub_.shutdown();
  } catch (const std::exception& e) {
    NODELET_ERROR_THROTTLE(5.0, "camera_info rejected: %s", e.what());
  }
}

void TrackingNodelet::imageCallback(const sensor_msgs::ImageConstPtr& msg) {
  cv::Mat gray;
  std::string error;
  if (!toMono8(*msg, &gray, &error)) {
    NODELET_ERROR_THROTTLE(2.0, "image dropped: %s", error.c_str());
    return;
  }
  std::lock_guard<std::mutex> lock(mutex_);
  if (!system_) {
    NODELET_WARN_THROTTLE(5.0, "image dropped: no calibration yet (set ~calibration_file or publish camera_info)");
    return;
  }
  const auto& camera = system_->camera();
  if (gray.cols != camera.width() || gray.rows != camera.height()) {
    NODELET_ERROR_THROTTLE(2.0, "image dropped: size %dx%d, calibration is %dx%d", gray.cols, gray.rows,
                           camera.width(), camera.height());
    return;
  }
  if (have_last_stamp_ && msg->header.stamp <= last_stamp_) {
    NODELET_ERROR_THROTTLE(2.0, "image dropped: stamp %.9f does not increase (last %.9f)",
                           msg->header.stamp.toSec(), last_stamp_.toSec());
    return;
  }
  have_last_stamp_ = true;
  last_stamp_ = msg->header.stamp;

  const auto start = std::chrono::steady_clock::now();
  FrameResult result;
  try {
    result = system_->process(gray, msg->header.stamp.toSec(),
                              stampText(msg->header.stamp.sec, msg->header.stamp.nsec));
  } catch (const std::exception& e) {
    NODELET_ERROR_THROTTLE(2.0, "frame %.9f not processed: %s", msg->header.stamp.toSec(), e.what());
    return;
  }
  const double ms = vitamin_e::elapsedMs(start);
  frame_id_ = !camera_frame_.empty() ? camera_frame_
                                     : (msg->header.frame_id.empty() ? "camera" : msg->header.frame_id);
  publishResult(result, msg->header, gray, ms);
}

void TrackingNodelet::reconfigure(vitamin_e::TrackingConfig& config, uint32_t) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (system_ && config.localization_only != dyn_.localization_only) {
    NODELET_INFO("localization only %s", config.localization_only ? "on: the map is not changed" : "off");
  }
  dyn_ = config;
  if (system_) system_->setLocalizationOnly(dyn_.localization_only);
}

bool TrackingNodelet::resetService(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!system_) {
    res.success = false;
    res.message = "no SLAM system yet (waiting for calibration)";
    return true;
  }
  system_->reset();
  track_history_.clear();
  res.success = true;
  res.message = "map and tracks reset; trajectory kept";
  NODELET_INFO("%s", res.message.c_str());
  return true;
}

bool TrackingNodelet::saveTrajectory(const std::string& path, std::string* message) {
  std::string error;
  if (!system_) {
    *message = "no SLAM system yet";
    return false;
  }
  const auto& trajectory = system_->trajectory();
  if (!vitamin_e::pipeline::saveTrajectoryTum(trajectory, path, &error)) {
    *message = "cannot write trajectory " + path + ": " + error;
    return false;
  }
  *message = "trajectory (" + std::to_string(trajectory.size()) + " poses, TUM) written to " + path;
  return true;
}

bool TrackingNodelet::saveMap(const std::string& path, std::string* message) {
  std::string error;
  if (!system_) {
    *message = "no SLAM system yet";
    return false;
  }
  const vitamin_e::map::MapFileContents contents = system_->exportMap();
  if (!vitamin_e::map::saveMapFile(contents, path, &error)) {
    *message = "cannot write map " + path + ": " + error;
    return false;
  }
  *message = "map (" + vitamin_e::map::mapFileHeader(contents) + ") written to " + path;
  return true;
}

bool TrackingNodelet::exportPoints(const std::string& path, std::string* message) {
  std::string error;
  if (!system_) {
    *message = "no SLAM system yet";
    return false;
  }
  const auto points = system_->mapPoints();
  if (!vitamin_e::pipeline::saveMapPly(points, path, &error)) {
    *message = "cannot write map points " + path + ": " + error;
    return false;
  }
  *message = "map points (" + std::to_string(points.size()) + ", PLY) written to " + path;
  return true;
}

bool TrackingNodelet::saveTrajectoryService(vitamin_e::SaveFile::Request& req, vitamin_e::SaveFile::Response& res) {
  std::lock_guard<std::mutex> lock(mutex_);
  const std::string path = req.path.empty() ? trajectory_file_ : req.path;
  if (path.empty()) {
    res.success = false;
    res.message = "no path given and ~trajectory_file not set";
    return true;
  }
  res.success = saveTrajectory(path, &res.message);
  NODELET_INFO("%s", res.message.c_str());
  return true;
}

bool TrackingNodelet::saveMapService(vitamin_e::SaveFile::Request& req, vitamin_e::SaveFile::Response& res) {
  std::lock_guard<std::mutex> lock(mutex_);
  const std::string path = req.path.empty() ? save_map_ : req.path;
  if (path.empty()) {
    res.success = false;
    res.message = "no path given and ~save_map not set";
    return true;
  }
  res.success = saveMap(path, &res.message);
  NODELET_INFO("%s", res.message.c_str());
  return true;
}

bool TrackingNodelet::exportPointsService(vitamin_e::SaveFile::Request& req, vitamin_e::SaveFile::Response& res) {
  std::lock_guard<std::mutex> lock(mutex_);
  const std::string path = req.path.empty() ? export_points_ : req.path;
  if (path.empty()) {
    res.success = false;
    res.message = "no path given and ~export_points not set";
    return true;
  }
  res.success = exportPoints(path, &res.message);
  NODELET_INFO("%s", res.message.c_str());
  return true;
}

}  // namespace vitamin_e_ros

PLUGINLIB_EXPORT_CLASS(vitamin_e_ros::TrackingNodelet, nodelet::Nodelet)
