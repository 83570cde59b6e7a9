#include "tracking_nodelet.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <exception>
#include <future>

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

// Frames the SLAM queue holds in bag mode (~process_all_frames): enough to hand over without a
// gap; more wait in the subscriber's queue.
constexpr std::size_t kBagQueueFrames = 4;

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
  pnh.param("debug_frame_delay", debug_frame_delay_s_, 0.0);
  std::string config_file, calibration_file;
  pnh.param<std::string>("config_file", config_file, "");
  pnh.param<std::string>("calibration_file", calibration_file, "");
  if (!(time_jump_threshold_s_ > 0.0)) {
    NODELET_FATAL("~time_jump_threshold must be > 0 s (got %g)", time_jump_threshold_s_);
    return;
  }
  if (!(debug_frame_delay_s_ >= 0.0 && debug_frame_delay_s_ <= 60.0)) {
    NODELET_FATAL("~debug_frame_delay must be in [0, 60] s (got %g)", debug_frame_delay_s_);
    return;
  }
  if (debug_frame_delay_s_ > 0.0) {
    NODELET_WARN("~debug_frame_delay %.3f s: every frame is held that long before it is processed (for tests)",
                 debug_frame_delay_s_);
  }
  // The SLAM thread's input: live, the newest frame only (a frame arriving while one waits
  // replaces it); bags, a few frames and the callback waits when they are full (the rest wait in
  // the subscriber's queue, ~queue_size).
  queue_ = std::make_unique<SlamQueue<QueuedFrame>>(process_all_frames_ ? kBagQueueFrames : 1, !process_all_frames_);

  try {
    if (!config_file.empty()) {
      system_config_ = vitamin_e::pipeline::loadSystemConfig(config_file);
    }
    system_config_.validate();
  } catch (const std::exception& e) {
    NODELET_FATAL("~config_file '%s': %s (no subscription: fix the config and restart)", config_file.c_str(), e.what());
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
  // Images on their own callback queue and thread: in bag mode the callback waits while the
  // SLAM queue is full, and nothing else (services, reconfigure, camera_info, IMU) waits with it.
  ros::NodeHandle image_nh(nh);
  image_nh.setCallbackQueue(&image_queue_);
  it_ = std::make_unique<image_transport::ImageTransport>(image_nh);
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
  reconfigure_server_->setCallback([this](vitamin_e::TrackingConfig& c, uint32_t level) { reconfigure(c, level); });

  reset_srv_ = pnh.advertiseService("reset", &TrackingNodelet::resetService, this);
  save_trajectory_srv_ = pnh.advertiseService("save_trajectory", &TrackingNodelet::saveTrajectoryService, this);
  save_map_srv_ = pnh.advertiseService("save_map", &TrackingNodelet::saveMapService, this);
  export_points_srv_ = pnh.advertiseService("export_points", &TrackingNodelet::exportPointsService, this);

  // Diagnostics are published from their own thread (below): they never wait for a frame being
  // processed. Every publisher and every subscription but the images' is on the nodelet's
  // single-threaded queue: nodelet::Loader may delete a nodelet inside a callback of one of its
  // queues after the other queue is gone, and roscpp then crashes removing the callbacks of that
  // other queue's publishers (seen with the diagnostics publisher on the multi-threaded queue).
  // The image queue (images and camera_info) is this nodelet's own: shut down and drained in
  // the destructor.
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
                     "set ~rectified false if the file is the rectified camera's",
                     image_topic.c_str());
      }
      if (!createSystem(calibration.camera)) return;
    } catch (const std::exception& e) {
      NODELET_FATAL("~calibration_file '%s': %s", calibration_file.c_str(), e.what());
      return;
    }
  } else {
    // On the images' queue: camera_info comes just before its image, and in one thread it is
    // taken first (on another queue the first images would find no calibration yet).
    info_sub_ = image_nh.subscribe("camera_info", 1, &TrackingNodelet::cameraInfoCallback, this);
    NODELET_INFO("no ~calibration_file: waiting for %s (%s)", info_sub_.getTopic().c_str(),
                 rectified_ ? "rectified image: P, no distortion" : "raw image: K and D");
  }
  if (!imu_topic_.empty()) {
    // On the nodelet's queue, which no frame holds up: every sample is taken as it arrives,
    // before the SLAM thread reaches the frames of its time (gravity window before them).
    imu_sub_ = nh.subscribe(imu_topic_, 2000, &TrackingNodelet::imuCallback, this);
  }
  publishBodyTransform();  // before any frame: the SLAM thread sends it later otherwise
  if (!subscribeImages(image_nh, pnh, queue_size)) return;
  image_thread_ = std::thread([this] {
    // disable() (destructor) wakes the wait at once; the timeout only bounds an idle wait.
    while (image_queue_.isEnabled()) image_queue_.callAvailable(ros::WallDuration(1.0));
  });
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

bool TrackingNodelet::subscribeImages(ros::NodeHandle& image_nh, ros::NodeHandle& pnh, int queue_size) {
  // The transport is the nodelet's own ~image_transport (image_transport's default reads the
  // manager's private namespace instead).
  const image_transport::TransportHints hints("raw", ros::TransportHints(), pnh);
  transport_ = hints.getTransport();
  const auto loadable = it_->getLoadableTransports();
  const bool available =
      std::find(loadable.begin(), loadable.end(), "image_transport/" + transport_) != loadable.end() ||
      std::find(loadable.begin(), loadable.end(), transport_) != loadable.end();
  const uint32_t queue = static_cast<uint32_t>(std::max(1, queue_size));
  const char* mode = process_all_frames_ ? "every frame processed: the SLAM queue waits when full"
                                         : "live: the SLAM takes the newest frame, stale frames are dropped";
  if (available) {
    image_sub_ = it_->subscribe("image", queue, &TrackingNodelet::imageCallback, this, hints);
    NODELET_INFO("subscribed to %s (transport %s, queue %d, %s)", image_sub_.getTopic().c_str(), transport_.c_str(),
                 queue_size, mode);
    return true;
  }
  if (transport_ == "compressed") {
    // Debian's ROS has no compressed_image_transport: read the CompressedImage topic directly.
    compressed_sub_ = image_nh.subscribe(image_nh.resolveName("image") + "/compressed", queue,
                                         &TrackingNodelet::compressedCallback, this);
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
  NODELET_INFO("camera: %s", camera.describe().c_str());
  bool localization_only = false;
  {
    std::lock_guard<std::mutex> lock(options_mutex_);
    localization_only = dyn_.localization_only;
  }
  if (loaded_map_) {
    try {
      system_->loadMap(*loaded_map_);
    } catch (const std::exception& e) {
      NODELET_FATAL("~load_map '%s': %s (no subscription: fix the file or the parameter and restart)",
                    load_map_.c_str(), e.what());
      system_.reset();
      image_sub_.shutdown();
      compressed_sub_.shutdown();
      info_sub_.shutdown();
      return false;
    }
    loaded_map_.reset();
    NODELET_INFO("relocalizing in the loaded map %s%s", load_map_.c_str(),
                 localization_only ? " (localization only)" : "");
  }
  system_->setLocalizationOnly(localization_only);
  updateSnapshot();
  // From here on system_ and the [SLAM] state are the SLAM thread's (the thread's start orders
  // the writes above before its first read).
  camera_width_ = camera.width();
  camera_height_ = camera.height();
  slam_thread_ = std::thread([this] { slamLoop(); });
  calibrated_ = true;
  {
    std::lock_guard<std::mutex> lock(stats_mutex_);
    stats_.calibrated = true;
  }
  return true;
}

void TrackingNodelet::stopThreads() {
  // The order makes the shutdown deterministic: a callback blocked on the full queue is woken
  // (the frame is discarded) before its subscription is shut down (which waits for it), and
  // the SLAM thread ends its frame (a held one is discarded) before the publishers go away.
  if (queue_) queue_->close();
  image_sub_.shutdown();
  compressed_sub_.shutdown();
  info_sub_.shutdown();
  image_queue_.disable();
  if (image_thread_.joinable()) image_thread_.join();
  image_queue_.clear();
  if (slam_thread_.joinable()) slam_thread_.join();
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
  stopThreads();
  // The SLAM thread has ended: its state is this thread's now.
  if (system_) {  // stderr: rosout may be gone at shutdown
    const auto q = queue_->counts();
    std::fprintf(stderr,
                 "[vitamin_e] %zu frames processed, %zu tracked, %d init retries, %d relocalizations, %u segment(s); "
                 "%zu frames dropped by the live queue, %zu still queued at shutdown (not processed)\n%s",
                 finished_processed_ + system_->framesProcessed(), finished_tracked_ + system_->framesTracked(),
                 finished_retries_ + system_->initRetries(), finished_relocalizations_ + system_->relocalizations(),
                 segment_, q.dropped, q.discarded, system_->timings().table().c_str());
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
  if (calibrated_) {
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
  enqueue(std::move(gray), msg->header);
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
  enqueue(std::move(gray), msg->header);
}

void TrackingNodelet::enqueue(cv::Mat gray, const std_msgs::Header& header) {
  if (!calibrated_) {
    noteRejected();
    NODELET_WARN_THROTTLE(5.0, "image dropped: no calibration yet (set ~calibration_file or publish camera_info)");
    return;
  }
  if (gray.cols != camera_width_ || gray.rows != camera_height_) {
    noteRejected();
    NODELET_ERROR_THROTTLE(2.0, "image dropped: size %dx%d, calibration is %dx%d", gray.cols, gray.rows, camera_width_,
                           camera_height_);
    return;
  }
  QueuedFrame frame;
  frame.gray = std::move(gray);
  frame.header = header;
  frame.received_wall = ros::WallTime::now().toSec();
  queue_->push(std::move(frame));  // false only when shutting down
}

void TrackingNodelet::slamLoop() {
  std::optional<QueuedFrame> frame;
  SlamQueue<QueuedFrame>::Command command;
  while (queue_->next(&frame, &command)) {
    if (command) {
      command();
      continue;
    }
    {
      std::lock_guard<std::mutex> lock(stats_mutex_);
      stats_.queue_wait_s.push_back(ros::WallTime::now().toSec() - frame->received_wall);
      while (stats_.queue_wait_s.size() > 200) stats_.queue_wait_s.pop_front();
    }
    // ~debug_frame_delay: the frame is in progress for that long (a slow SLAM, for tests);
    // shutting down ends the wait, and the frame is not processed.
    if (debug_frame_delay_s_ > 0.0 && !queue_->waitFor(debug_frame_delay_s_)) continue;
    processFrame(*frame);
  }
}

bool TrackingNodelet::runOnSlamThread(const std::function<void()>& work, std::string* why) {
  if (!calibrated_) {
    *why = "no SLAM system yet (waiting for calibration)";
    return false;
  }
  auto done = std::make_shared<std::promise<void>>();
  std::future<void> finished = done->get_future();
  const bool posted = queue_->post([&work, done] {
    try {
      work();
      done->set_value();
    } catch (...) {
      done->set_exception(std::current_exception());
    }
  });
  if (!posted) {
    *why = "shutting down";
    return false;
  }
  try {
    finished.get();  // the frame in progress, if any, then this work: never the queued frames
  } catch (const std::exception& e) {
    *why = e.what();
    return false;
  }
  return true;
}

void TrackingNodelet::processFrame(const QueuedFrame& frame) {
  const std_msgs::Header& header = frame.header;
  {
    std::lock_guard<std::mutex> lock(options_mutex_);
    options_ = dyn_;
  }
  if (system_->localizationOnly() != options_.localization_only) {
    system_->setLocalizationOnly(options_.localization_only);
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
    result = system_->process(frame.gray, header.stamp.toSec(), stampText(header.stamp.sec, header.stamp.nsec));
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
  updateSnapshot();
  // Everything published is in the map frame: T_map_c = T_map_w T_w_c, p_map = T_map_w p_w.
  if (have_map_) {
    result.T_w_c = T_map_w_ * result.T_w_c;
    for (auto& p : result.points) {
      if (p.has_position) p.p_w = T_map_w_ * p.p_w;
    }
  }
  publishResult(result, frame, ms);
}

void TrackingNodelet::updateSnapshot() {
  const auto& trajectory = system_->trajectory();
  const std::string note = segmentNote();
  std::lock_guard<std::mutex> lock(snapshot_mutex_);
  auto& current = snapshot_.current;
  // Poses are appended, and only the newest is refined within its own frame: copy from the
  // last one copied (all of them if the trajectory is not the one copied so far).
  std::size_t from = current.empty() ? 0 : current.size() - 1;
  if (trajectory.size() < current.size()) from = 0;
  current.resize(from);
  current.insert(current.end(), trajectory.begin() + static_cast<std::ptrdiff_t>(from), trajectory.end());
  snapshot_.T_map_w = T_map_w_;
  snapshot_.note = note;
}

void TrackingNodelet::startSegment(const std::string& why) {
  {
    std::lock_guard<std::mutex> lock(snapshot_mutex_);
    TrajectorySegment done;
    done.note = segmentNote();
    for (auto e : system_->trajectory()) {
      e.T_w_c = T_map_w_ * e.T_w_c;
      done.poses.push_back(e);
    }
    if (!done.poses.empty()) snapshot_.finished.push_back(std::move(done));
    snapshot_.current.clear();
  }
  finished_processed_ += system_->framesProcessed();
  finished_tracked_ += system_->framesTracked();
  finished_retries_ += system_->initRetries();
  finished_relocalizations_ += system_->relocalizations();
  // A fresh system: no map, no tracks and no last stamp (System::reset keeps the stamp).
  system_ = std::make_unique<vitamin_e::pipeline::System>(system_config_, camera_);
  system_->setLocalizationOnly(options_.localization_only);
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
  updateSnapshot();
  std::lock_guard<std::mutex> lock(stats_mutex_);
  stats_.segment = segment_;
}

std::string TrackingNodelet::segmentNote() const {
  // Why the segment began, and its map (each segment has its own).
  return segment_note_ + (map_description_.empty() ? "" : "; " + map_description_);
}

void TrackingNodelet::reconfigure(vitamin_e::TrackingConfig& config, uint32_t) {
  // Taken by the SLAM thread at its next frame; never waits for the one in progress.
  std::lock_guard<std::mutex> lock(options_mutex_);
  if (calibrated_ && config.localization_only != dyn_.localization_only) {
    NODELET_INFO("localization only %s (from the next frame)",
                 config.localization_only ? "on: the map is not changed" : "off");
  }
  dyn_ = config;
}

bool TrackingNodelet::resetService(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res) {
  unsigned segment = 0;
  std::string why;
  res.success = runOnSlamThread(
      [&] {
        startSegment("~reset");
        segment = segment_;
      },
      &why);
  if (!res.success) {
    res.message = why;
    return true;
  }
  res.message = "map, tracks, last stamp and path reset; trajectory segment " + std::to_string(segment) +
                " begins (earlier segments kept)";
  NODELET_INFO("%s", res.message.c_str());
  return true;
}

bool TrackingNodelet::saveTrajectory(const std::string& path, std::string* message) {
  if (!calibrated_) {
    *message = "no SLAM system yet";
    return false;
  }
  // A copy of the snapshot: the SLAM thread goes on while the file is written.
  std::vector<TrajectorySegment> all;
  {
    std::lock_guard<std::mutex> lock(snapshot_mutex_);
    all = snapshot_.finished;
    TrajectorySegment current;
    current.note = snapshot_.note;
    current.poses.reserve(snapshot_.current.size());
    for (auto e : snapshot_.current) {
      e.T_w_c = snapshot_.T_map_w * e.T_w_c;
      current.poses.push_back(e);
    }
    if (!current.poses.empty() || all.empty()) all.push_back(std::move(current));
  }
  std::size_t poses = 0;
  for (const auto& s : all) poses += s.poses.size();
  const std::string header = "T_map_c: camera (optical) in '" + map_frame_ + "'; each segment has its own map";
  std::string error;
  if (!saveSegmentsTum(all, header, path, &error)) {
    *message = "cannot write trajectory " + path + ": " + error;
    return false;
  }
  *message = "trajectory (" + std::to_string(poses) + " poses in " + std::to_string(all.size()) +
             " segment(s), TUM) written to " + path;
  if (queue_) {
    // Said, so that a caller knows the file is a snapshot of a run still going on.
    const auto q = queue_->counts();
    const std::size_t pending = q.waiting + (q.busy ? 1 : 0);
    if (pending > 0) *message += "; " + std::to_string(pending) + " frame(s) not processed yet";
  }
  return true;
}

bool TrackingNodelet::saveMap(const std::string& path, std::string* message) {
  return writeMap(system_->exportMap(), path, message);
}

bool TrackingNodelet::exportPoints(const std::string& path, std::string* message) {
  return writePoints(mapPointsInMap(), path, message);
}

std::vector<vitamin_e::pipeline::MapPoint3> TrackingNodelet::mapPointsInMap() const {
  auto points = system_->mapPoints();
  for (auto& p : points) p.p_w = T_map_w_ * p.p_w;
  return points;
}

bool TrackingNodelet::writeMap(const vitamin_e::map::MapFileContents& contents, const std::string& path,
                               std::string* message) {
  std::string error;
  if (!vitamin_e::map::saveMapFile(contents, path, &error)) {
    *message = "cannot write map " + path + ": " + error;
    return false;
  }
  *message = "map (" + vitamin_e::map::mapFileHeader(contents) + ") written to " + path;
  return true;
}

bool TrackingNodelet::writePoints(const std::vector<vitamin_e::pipeline::MapPoint3>& points, const std::string& path,
                                  std::string* message) {
  std::string error;
  if (!vitamin_e::pipeline::saveMapPly(points, path, &error)) {
    *message = "cannot write map points " + path + ": " + error;
    return false;
  }
  *message = "map points (" + std::to_string(points.size()) + " in '" + map_frame_ + "', PLY) written to " + path;
  return true;
}

bool TrackingNodelet::saveTrajectoryService(vitamin_e::SaveFile::Request& req, vitamin_e::SaveFile::Response& res) {
  auto save = [this](const std::string& path, std::string* message) { return saveTrajectory(path, message); };
  if (answerSaveFile(req, trajectory_file_, "trajectory_file", "", &res, save)) NODELET_INFO("%s", res.message.c_str());
  return true;
}

bool TrackingNodelet::saveMapService(vitamin_e::SaveFile::Request& req, vitamin_e::SaveFile::Response& res) {
  // The map is the SLAM thread's: copied there between two frames, written here.
  auto save = [this](const std::string& path, std::string* message) {
    vitamin_e::map::MapFileContents contents;
    if (!runOnSlamThread([&] { contents = system_->exportMap(); }, message)) return false;
    return writeMap(contents, path, message);
  };
  if (answerSaveFile(req, save_map_, "save_map", "", &res, save)) NODELET_INFO("%s", res.message.c_str());
  return true;
}

bool TrackingNodelet::exportPointsService(vitamin_e::SaveFile::Request& req, vitamin_e::SaveFile::Response& res) {
  auto save = [this](const std::string& path, std::string* message) {
    std::vector<vitamin_e::pipeline::MapPoint3> points;
    if (!runOnSlamThread([&] { points = mapPointsInMap(); }, message)) return false;
    return writePoints(points, path, message);
  };
  if (answerSaveFile(req, export_points_, "export_points", "", &res, save)) NODELET_INFO("%s", res.message.c_str());
  return true;
}

}  // namespace vitamin_e_ros

PLUGINLIB_EXPORT_CLASS(vitamin_e_ros::TrackingNodelet, nodelet::Nodelet)
