#include "tracking_nodelet.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <exception>

#include <pluginlib/class_list_macros.hpp>

#include <geometry_msgs/PoseStamped.h>
#include <nav_msgs/Odometry.h>
#include <sensor_msgs/PointCloud2.h>

#include "save_file_service.h"
#include "vitamin_e/TrackedFrame.h"
#include "vitamin_e/TrackingStatus.h"
#include "vitamin_e/ros/conversions.h"

namespace vitamin_e_ros {

using vitamin_e::pipeline::FrameResult;

namespace {

// ~rectified: true, false or "auto" (from the image topic's name).
std::string rectifiedParam(ros::NodeHandle& pnh) {
  bool b = false;
  if (pnh.getParam("rectified", b)) return b ? "true" : "false";
  std::string s = "auto";
  pnh.getParam("rectified", s);
  return s;
}

}  // namespace

void TrackingNodelet::onInit() {
  ros::NodeHandle& nh = getNodeHandle();
  ros::NodeHandle& pnh = getPrivateNodeHandle();

  if (!readFrameParameters(pnh)) return;
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
  pnh.param("reset_on_time_jump", reset_on_time_jump_, true);
  pnh.param("time_jump_threshold", time_jump_threshold_s_, 1.0);
  int queue_size = 1;
  pnh.param("queue_size", queue_size, process_all_frames_ ? 10000 : 1);
  std::string config_file, calibration_file;
  pnh.param<std::string>("config_file", config_file, "");
  pnh.param<std::string>("calibration_file", calibration_file, "");
  if (!(time_jump_threshold_s_ > 0.0)) {
    NODELET_FATAL("~time_jump_threshold must be > 0 s (got %g)", time_jump_threshold_s_);
    return;
  }

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
  static_broadcaster_ = std::make_unique<tf2_ros::StaticTransformBroadcaster>();
  if (!base_frame_.empty() || (!imu_topic_.empty() && calibration_file.empty())) {
    tf_buffer_ = std::make_unique<tf2_ros::Buffer>();
    tf_listener_ = std::make_unique<tf2_ros::TransformListener>(*tf_buffer_, nh);
  }
  if (!odom_frame_.empty() && !base_frame_.empty()) {
    NODELET_INFO("REP-105: publishing %s -> %s (from %s -> %s)", map_frame_.c_str(), odom_frame_.c_str(),
                 odom_frame_.c_str(), base_frame_.c_str());
  } else if (!base_frame_.empty()) {
    NODELET_INFO("publishing %s -> %s (the camera under the base frame)", map_frame_.c_str(), base_frame_.c_str());
  }

  reconfigure_server_ =
      std::make_unique<dynamic_reconfigure::Server<vitamin_e::TrackingConfig>>(reconfigure_mutex_, pnh);
  reconfigure_server_->setCallback(
      [this](vitamin_e::TrackingConfig& c, uint32_t level) { reconfigure(c, level); });

  reset_srv_ = pnh.advertiseService("reset", &TrackingNodelet::resetService, this);
  save_trajectory_srv_ = pnh.advertiseService("save_trajectory", &TrackingNodelet::saveTrajectoryService, this);
  save_map_srv_ = pnh.advertiseService("save_map", &TrackingNodelet::saveMapService, this);
  export_points_srv_ = pnh.advertiseService("export_points", &TrackingNodelet::exportPointsService, this);

  // Diagnostics are published from their own thread (below): they never wait for a frame being
  // processed. Every subscription and publisher is on the nodelet's single-threaded queue:
  // nodelet::Loader may delete a nodelet inside a callback of one of its queues after the other
  // queue is gone, and roscpp then crashes removing the callbacks of that other queue's
  // publishers (seen with the diagnostics publisher on the multi-threaded queue).
  diagnostics_ = std::make_unique<diagnostic_updater::Updater>(nh, pnh, getName());
  diagnostics_->setHardwareID(camera_frame_.empty() ? "camera" : camera_frame_);
  diagnostics_->add("vitamin_e tracking", this, &TrackingNodelet::diagnose);
  double diagnostic_period = 1.0;
  pnh.param("diagnostic_period", diagnostic_period, 1.0);
  diagnostic_period = std::max(0.05, diagnostic_period);
  diagnostics_thread_ = std::thread([this, diagnostic_period] {
    std::unique_lock<std::mutex> lock(diagnostics_wait_mutex_);
    while (!diagnostics_wake_.wait_for(lock, std::chrono::duration<double>(diagnostic_period),
                                       [this] { return diagnostics_stop_; })) {
      lock.unlock();
      diagnostics_->force_update();
      lock.lock();
    }
  });

  const std::string rectified = rectifiedParam(pnh);
  if (rectified != "auto" && rectified != "true" && rectified != "false") {
    NODELET_FATAL("~rectified must be true, false or auto (got '%s')", rectified.c_str());
    return;
  }
  const std::string image_topic = nh.resolveName("image");
  rectified_ = rectified == "true" || (rectified == "auto" && isRectifiedTopic(image_topic));

  have_calibration_file_ = !calibration_file.empty();
  if (have_calibration_file_) {
    try {
      const auto calibration = vitamin_e::camera::loadCalibration(calibration_file);
      T_b_c_ = calibration.T_b_c;
      if (rectified_) {
        NODELET_WARN("%s looks rectified, but ~calibration_file describes the camera with its distortion: "
                     "set ~rectified false if the file is the rectified camera's", image_topic.c_str());
      }
      if (!createSystem(calibration.camera)) return;
    } catch (const std::exception& e) {
      NODELET_FATAL("~calibration_file '%s': %s", calibration_file.c_str(), e.what());
      return;
    }
  } else {
    info_sub_ = nh.subscribe("camera_info", 1, &TrackingNodelet::cameraInfoCallback, this);
    NODELET_INFO("no ~calibration_file: waiting for %s (%s)", info_sub_.getTopic().c_str(),
                 rectified_ ? "rectified image: P, no distortion" : "raw image: K and D");
  }
  if (!imu_topic_.empty()) {
    // In the image callbacks' queue: samples arriving before an image are taken before it.
    imu_sub_ = nh.subscribe(imu_topic_, 2000, &TrackingNodelet::imuCallback, this);
  }
  if (!subscribeImages(nh, pnh, queue_size)) return;
  publishBodyTransform();
}

bool TrackingNodelet::readFrameParameters(ros::NodeHandle& pnh) {
  pnh.param<std::string>("map_frame", map_frame_, "map");
  pnh.param<std::string>("camera_frame", camera_frame_, "");
  pnh.param<std::string>("odom_frame", odom_frame_, "");
  pnh.param<std::string>("base_frame", base_frame_, "");
  pnh.param<std::string>("body_frame", body_frame_, "");
  pnh.param<std::string>("imu_topic", imu_topic_, "");
  pnh.param("gravity_window", gravity_window_s_, 1.0);
  std::string convention;
  pnh.param<std::string>("map_convention", convention, "z_up");
  if (convention != "z_up" && convention != "optical") {
    NODELET_FATAL("~map_convention must be z_up or optical (got '%s')", convention.c_str());
    return false;
  }
  if (!(gravity_window_s_ > 0.0)) {
    NODELET_FATAL("~gravity_window must be > 0 s (got %g)", gravity_window_s_);
    return false;
  }
  optical_map_ = convention == "optical";
  if (optical_map_) {
    NODELET_INFO("map frame '%s': the first camera's optical frame (~map_convention optical: z forward, y down)",
                 map_frame_.c_str());
  } else if (!imu_topic_.empty()) {
    NODELET_INFO("map frame '%s': z up along gravity from %s (%.2f s of accelerometer before the initialization), "
                 "x the first camera's heading",
                 map_frame_.c_str(), imu_topic_.c_str(), gravity_window_s_);
  } else if (!base_frame_.empty() && base_frame_ != body_frame_) {
    NODELET_INFO("map frame '%s': the pose of %s when the first image was taken (REP-105; z up for a level robot)",
                 map_frame_.c_str(), base_frame_.c_str());
  } else {
    NODELET_INFO("map frame '%s': the first camera in ROS axes (x forward, z up): the map is only as level as "
                 "the first camera (set ~imu_topic or ~base_frame for a level map)",
                 map_frame_.c_str());
  }
  return true;
}

bool TrackingNodelet::subscribeImages(ros::NodeHandle& nh, ros::NodeHandle& pnh, int queue_size) {
  // The transport is the nodelet's own ~image_transport (image_transport's default reads the
  // manager's private namespace instead).
  const image_transport::TransportHints hints("raw", ros::TransportHints(), pnh);
  transport_ = hints.getTransport();
  const auto loadable = it_->getLoadableTransports();
  const bool available = std::find(loadable.begin(), loadable.end(), "image_transport/" + transport_) != loadable.end() ||
                         std::find(loadable.begin(), loadable.end(), transport_) != loadable.end();
  const uint32_t queue = static_cast<uint32_t>(std::max(1, queue_size));
  const char* mode = process_all_frames_ ? "every frame processed" : "live: stale frames dropped";
  if (available) {
    image_sub_ = it_->subscribe("image", queue, &TrackingNodelet::imageCallback, this, hints);
    NODELET_INFO("subscribed to %s (transport %s, queue %d, %s)", image_sub_.getTopic().c_str(), transport_.c_str(),
                 queue_size, mode);
    return true;
  }
  if (transport_ == "compressed") {
    // Debian's ROS has no compressed_image_transport: read the CompressedImage topic directly.
    compressed_sub_ = nh.subscribe(nh.resolveName("image") + "/compressed", queue, &TrackingNodelet::compressedCallback,
                                   this);
    NODELET_INFO("image_transport plugin 'compressed' not installed: subscribed to %s (sensor_msgs/CompressedImage, "
                 "decoded with OpenCV; queue %d, %s)",
                 compressed_sub_.getTopic().c_str(), queue_size, mode);
    return true;
  }
  std::string names;
  for (const auto& l : loadable) names += (names.empty() ? "" : ", ") + l;
  NODELET_FATAL("~image_transport '%s' is not installed (installed: %s; 'compressed' is decoded here even without "
                "its plugin): no image subscription",
                transport_.c_str(), names.c_str());
  return false;
}

bool TrackingNodelet::createSystem(const vitamin_e::camera::Camera& camera) {
  try {
    system_ = std::make_unique<vitamin_e::pipeline::System>(system_config_, camera);
  } catch (const std::exception& e) {
    NODELET_FATAL("cannot start the SLAM system: %s", e.what());
    return false;
  }
  camera_ = camera;
  {
    std::lock_guard<std::mutex> lock(stats_mutex_);
    stats_.calibrated = true;
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
  if (diagnostics_thread_.joinable()) {
    {
      std::lock_guard<std::mutex> lock(diagnostics_wait_mutex_);
      diagnostics_stop_ = true;
    }
    diagnostics_wake_.notify_all();
    diagnostics_thread_.join();
  }
  std::lock_guard<std::mutex> lock(mutex_);
  if (system_) {  // stderr: rosout may be gone at shutdown
    std::fprintf(stderr,
                 "[vitamin_e] %zu frames processed, %zu tracked, %d init retries, %d relocalizations, %u segment(s)\n%s",
                 finished_processed_ + system_->framesProcessed(), finished_tracked_ + system_->framesTracked(),
                 finished_retries_ + system_->initRetries(), finished_relocalizations_ + system_->relocalizations(),
                 segment_, system_->timings().table().c_str());
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
    if (createSystem(cameraFromInfo(*msg, rectified_))) info_sub_.shutdown();
  } catch (const std::exception& e) {
    NODELET_ERROR_THROTTLE(5.0, "camera_info rejected: %s", e.what());
  }
}

void TrackingNodelet::imuCallback(const sensor_msgs::ImuConstPtr& msg) {
  const auto& a = msg->linear_acceleration;
  std::lock_guard<std::mutex> lock(imu_mutex_);
  if (imu_frame_.empty()) imu_frame_ = msg->header.frame_id;
  // Bounded: a SLAM far behind a bag must not let the buffer grow without end (about 8 min at 200 Hz).
  if (gravity_.size() >= 100000) gravity_.dropBefore(gravity_.newest() - 2.0 * gravity_window_s_);
  gravity_.add(msg->header.stamp.toSec(), Eigen::Vector3d(a.x, a.y, a.z));
  ++imu_samples_;
}

void TrackingNodelet::imageCallback(const sensor_msgs::ImageConstPtr& msg) {
  noteReceived(msg->header.stamp);
  cv::Mat gray;
  std::string error;
  if (!toMono8(*msg, &gray, &error)) {
    noteRejected();
    NODELET_ERROR_THROTTLE(2.0, "image dropped: %s", error.c_str());
    return;
  }
  processFrame(gray, msg->header);
}

void TrackingNodelet::compressedCallback(const sensor_msgs::CompressedImageConstPtr& msg) {
  noteReceived(msg->header.stamp);
  cv::Mat gray;
  std::string error;
  if (!compressedToMono8(*msg, &gray, &error)) {
    noteRejected();
    NODELET_ERROR_THROTTLE(2.0, "image dropped: %s", error.c_str());
    return;
  }
  processFrame(gray, msg->header);
}

void TrackingNodelet::processFrame(const cv::Mat& gray, const std_msgs::Header& header) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!system_) {
    noteRejected();
    NODELET_WARN_THROTTLE(5.0, "image dropped: no calibration yet (set ~calibration_file or publish camera_info)");
    return;
  }
  if (gray.cols != camera_.width() || gray.rows != camera_.height()) {
    noteRejected();
    NODELET_ERROR_THROTTLE(2.0, "image dropped: size %dx%d, calibration is %dx%d", gray.cols, gray.rows,
                           camera_.width(), camera_.height());
    return;
  }
  if (have_last_stamp_ && header.stamp <= last_stamp_) {
    const double back = (last_stamp_ - header.stamp).toSec();
    if (reset_on_time_jump_ && back > time_jump_threshold_s_) {
      // A bag played again (--loop) or a clock reset: a new SLAM run instead of dropping every frame.
      char why[160];
      std::snprintf(why, sizeof(why), "stamp jumped back by %.3f s (%.3f -> %.3f)", back, last_stamp_.toSec(),
                    header.stamp.toSec());
      NODELET_WARN("%s: SLAM restarted, trajectory segment %u begins (~reset_on_time_jump)", why, segment_ + 1);
      startSegment(std::string("time jump: ") + why);
    } else {
      noteRejected();
      NODELET_ERROR_THROTTLE(2.0, "image dropped: stamp %.9f does not increase (last %.9f)", header.stamp.toSec(),
                             last_stamp_.toSec());
      return;
    }
  }
  have_last_stamp_ = true;
  last_stamp_ = header.stamp;

  frame_id_ = !camera_frame_.empty() ? camera_frame_ : (header.frame_id.empty() ? "camera" : header.frame_id);
  if (!body_tf_sent_) publishBodyTransform();
  const auto start = std::chrono::steady_clock::now();
  FrameResult result;
  try {
    result = system_->process(gray, header.stamp.toSec(), stampText(header.stamp.sec, header.stamp.nsec));
  } catch (const std::exception& e) {
    noteRejected();
    NODELET_ERROR_THROTTLE(2.0, "frame %.9f not processed: %s", header.stamp.toSec(), e.what());
    return;
  }
  const double ms = vitamin_e::elapsedMs(start);
  if (result.pose_valid && !have_map_) alignMap(result);
  if (!have_map_) {
    // Until the map is fixed: samples older than any later frame's gravity window are not needed.
    std::lock_guard<std::mutex> imu_lock(imu_mutex_);
    gravity_.dropBefore(header.stamp.toSec() - gravity_window_s_ - 1.0);
  }
  // Everything published is in the map frame: T_map_c = T_map_w T_w_c, p_map = T_map_w p_w.
  if (have_map_) {
    result.T_w_c = T_map_w_ * result.T_w_c;
    for (auto& p : result.points) {
      if (p.has_position) p.p_w = T_map_w_ * p.p_w;
    }
  }
  publishResult(result, header, gray, ms);
}

void TrackingNodelet::startSegment(const std::string& why) {
  if (system_) {
    TrajectorySegment done;
    done.note = segmentNote();
    for (auto e : system_->trajectory()) {
      e.T_w_c = T_map_w_ * e.T_w_c;
      done.poses.push_back(e);
    }
    if (!done.poses.empty()) finished_.push_back(std::move(done));
    finished_processed_ += system_->framesProcessed();
    finished_tracked_ += system_->framesTracked();
    finished_retries_ += system_->initRetries();
    finished_relocalizations_ += system_->relocalizations();
    // A fresh system: no map, no tracks and no last stamp (System::reset keeps the stamp).
    system_ = std::make_unique<vitamin_e::pipeline::System>(system_config_, camera_);
  }
  ++segment_;
  segment_note_ = why;
  have_last_stamp_ = false;
  have_map_ = false;
  T_map_w_ = Eigen::Isometry3d::Identity();
  map_description_.clear();
  last_map_points_ = ros::Time();
  track_history_.clear();
  path_.poses.clear();
  path_pub_.publish(path_);
  std::lock_guard<std::mutex> lock(stats_mutex_);
  stats_.segment = segment_;
}

std::string TrackingNodelet::segmentNote() const {
  // Why the segment began, and its map (each segment has its own).
  return segment_note_ + (map_description_.empty() ? "" : "; " + map_description_);
}

std::vector<TrajectorySegment> TrackingNodelet::segments() const {
  std::vector<TrajectorySegment> all = finished_;
  if (system_) {
    TrajectorySegment current;
    current.note = segmentNote();
    for (auto e : system_->trajectory()) {
      e.T_w_c = T_map_w_ * e.T_w_c;
      current.poses.push_back(e);
    }
    if (!current.poses.empty() || all.empty()) all.push_back(std::move(current));
  }
  return all;
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
  startSegment("~reset");
  res.success = true;
  res.message = "map, tracks, last stamp and path reset; trajectory segment " + std::to_string(segment_) +
                " begins (earlier segments kept)";
  NODELET_INFO("%s", res.message.c_str());
  return true;
}

bool TrackingNodelet::saveTrajectory(const std::string& path, std::string* message) {
  std::string error;
  if (!system_) {
    *message = "no SLAM system yet";
    return false;
  }
  const auto all = segments();
  std::size_t poses = 0;
  for (const auto& s : all) poses += s.poses.size();
  const std::string header = "T_map_c: camera (optical) in '" + map_frame_ + "'; each segment has its own map";
  if (!saveSegmentsTum(all, header, path, &error)) {
    *message = "cannot write trajectory " + path + ": " + error;
    return false;
  }
  *message = "trajectory (" + std::to_string(poses) + " poses in " + std::to_string(all.size()) +
             " segment(s), TUM) written to " + path;
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
  auto points = system_->mapPoints();
  for (auto& p : points) p.p_w = T_map_w_ * p.p_w;
  if (!vitamin_e::pipeline::saveMapPly(points, path, &error)) {
    *message = "cannot write map points " + path + ": " + error;
    return false;
  }
  *message = "map points (" + std::to_string(points.size()) + " in '" + map_frame_ + "', PLY) written to " + path;
  return true;
}

bool TrackingNodelet::saveTrajectoryService(vitamin_e::SaveFile::Request& req, vitamin_e::SaveFile::Response& res) {
  std::lock_guard<std::mutex> lock(mutex_);
  auto save = [this](const std::string& path, std::string* message) { return saveTrajectory(path, message); };
  if (answerSaveFile(req, trajectory_file_, "trajectory_file", "", &res, save)) NODELET_INFO("%s", res.message.c_str());
  return true;
}

bool TrackingNodelet::saveMapService(vitamin_e::SaveFile::Request& req, vitamin_e::SaveFile::Response& res) {
  std::lock_guard<std::mutex> lock(mutex_);
  auto save = [this](const std::string& path, std::string* message) { return saveMap(path, message); };
  if (answerSaveFile(req, save_map_, "save_map", "", &res, save)) NODELET_INFO("%s", res.message.c_str());
  return true;
}

bool TrackingNodelet::exportPointsService(vitamin_e::SaveFile::Request& req, vitamin_e::SaveFile::Response& res) {
  std::lock_guard<std::mutex> lock(mutex_);
  auto save = [this](const std::string& path, std::string* message) { return exportPoints(path, message); };
  if (answerSaveFile(req, export_points_, "export_points", "", &res, save)) NODELET_INFO("%s", res.message.c_str());
  return true;
}

}  // namespace vitamin_e_ros

PLUGINLIB_EXPORT_CLASS(vitamin_e_ros::TrackingNodelet, nodelet::Nodelet)
