#include "tracking_nodelet.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <exception>
#include <future>
#include <stdexcept>

#include <pluginlib/class_list_macros.hpp>

#include <geometry_msgs/PoseStamped.h>
#include <nav_msgs/Odometry.h>
#include <sensor_msgs/PointCloud2.h>

#include "save_file_service.h"
#include "vitamin_e/TrackedFrame.h"
#include "vitamin_e/TrackingStatus.h"
#include "vitamin_e/common/allocator.h"
#include "vitamin_e/ros/conversions.h"

namespace vitamin_e_ros {

using vitamin_e::pipeline::FrameResult;

namespace {

// Frames the SLAM queue holds in bag mode (~process_all_frames): enough to hand over without a
// gap; more wait in the subscriber's queue.
constexpr std::size_t kBagQueueFrames = 4;

}  // namespace

// A nodelet that cannot run says why and throws: the loader unloads it and its load request
// fails, so that `nodelet load` (and roslaunch with it) reports the failure.
std::runtime_error TrackingNodelet::fatal(const std::string& why) const {
  NODELET_FATAL("%s", why.c_str());
  return std::runtime_error(why);
}

void TrackingNodelet::onInit() {
  ros::NodeHandle& nh = getNodeHandle();
  ros::NodeHandle& pnh = getPrivateNodeHandle();
  const TrackingFiles files = loadConfiguration(pnh);
  // The SLAM thread's input: live, the newest frame only (a frame arriving while one waits
  // replaces it); bags, a few frames and the callback waits when they are full (the rest wait in
  // the subscriber's queue, ~queue_size).
  queue_ = std::make_unique<SlamQueue<QueuedFrame>>(params_.process_all_frames ? kBagQueueFrames : 1,
                                                    !params_.process_all_frames);
  // Images on their own callback queue and thread: in bag mode the callback waits while the
  // SLAM queue is full, and nothing else (services, reconfigure, camera_info, IMU) waits with it.
  ros::NodeHandle image_nh(nh);
  image_nh.setCallbackQueue(&image_queue_);
  // Whatever can stop the nodelet is checked before anything is advertised: the loader deletes
  // a nodelet whose onInit threw after its callback queues, and roscpp crashes removing the
  // callbacks of its publishers then.
  it_ = std::make_unique<image_transport::ImageTransport>(image_nh);
  checkTransport(pnh);
  const std::string image_topic = nh.resolveName("image");
  rectified_ = params_.rectified == "true" || (params_.rectified == "auto" && isRectifiedTopic(image_topic));
  if (files.calibration) {
    T_b_c_ = files.calibration->T_b_c;
    if (rectified_) {
      NODELET_WARN("%s looks rectified, but ~calibration_file describes the camera with its distortion: "
                   "set ~rectified false if the file is the rectified camera's",
                   image_topic.c_str());
    }
    makeSession(files.calibration->camera);
  } else {
    NODELET_INFO("no ~calibration_file: waiting for %s (%s)", nh.resolveName("camera_info").c_str(),
                 rectified_ ? "rectified image: P, no distortion" : "raw image: K and D");
  }

  advertise(pnh);
  tf_broadcaster_ = std::make_unique<tf2_ros::TransformBroadcaster>();
  static_broadcaster_ = std::make_unique<tf2_ros::StaticTransformBroadcaster>();
  if (!params_.base_frame.empty() || (!params_.imu_topic.empty() && params_.calibration_file.empty())) {
    tf_buffer_ = std::make_unique<tf2_ros::Buffer>();
    tf_listener_ = std::make_unique<tf2_ros::TransformListener>(*tf_buffer_, nh);
  }
  startDiagnostics(nh, pnh);
  if (runner_) startSlam();
  subscribe(nh, image_nh, pnh);
  started_ = true;
}

TrackingFiles TrackingNodelet::loadConfiguration(ros::NodeHandle& pnh) {
  ParamNotes notes;
  try {
    params_ = readTrackingParams(
        [&pnh](const std::string& name, XmlRpc::XmlRpcValue* value) { return pnh.getParam(name, *value); }, &notes);
  } catch (const std::exception& e) {
    throw fatal(std::string(e.what()) + " (the nodelet does not start: fix the parameter and restart)");
  }
  for (const auto& w : notes.warnings) NODELET_WARN("%s", w.c_str());
  for (const auto& i : notes.infos) NODELET_INFO("%s", i.c_str());
  if (params_.debug_frame_delay_s > 0.0) {
    NODELET_WARN("~debug_frame_delay %.3f s: every frame is held that long before it is processed (for tests)",
                 params_.debug_frame_delay_s);
  }
  if (params_.reuse_freed_memory) {
    const vitamin_e::AllocatorSetting allocator = vitamin_e::reuseFreedFrameBuffers();
    if (allocator.applied) {
      NODELET_INFO("~reuse_freed_memory: %s", allocator.what.c_str());
    } else {
      NODELET_WARN("~reuse_freed_memory: %s", allocator.what.c_str());
    }
  }
  logMapFrameSource();
  TrackingFiles files;
  try {
    files = loadTrackingFiles(params_);
  } catch (const std::exception& e) {
    throw fatal(std::string(e.what()) + " (the nodelet does not start: fix the file or the parameter and restart)");
  }
  system_config_ = files.system_config;
  loaded_map_ = std::move(files.map);
  NODELET_INFO("SLAM config %s:\n%s", params_.config_file.empty() ? "(defaults)" : params_.config_file.c_str(),
               system_config_.describe().c_str());
  if (loaded_map_) {
    NODELET_INFO("~load_map %s: %s", params_.load_map.c_str(), vitamin_e::map::mapFileHeader(*loaded_map_).c_str());
  }
  return files;
}

void TrackingNodelet::subscribe(ros::NodeHandle& nh, ros::NodeHandle& image_nh, ros::NodeHandle& pnh) {
  // camera_info on the images' queue: it comes just before its image, and in one thread it is
  // taken first (on another queue the first images would find no calibration yet). Kept after
  // the calibration, to say when it changes.
  info_sub_ = image_nh.subscribe("camera_info", 1, &TrackingNodelet::cameraInfoCallback, this);
  if (!params_.imu_topic.empty()) {
    // On the nodelet's queue, which no frame holds up: every sample is taken as it arrives,
    // before the SLAM thread reaches the frames of its time (gravity window before them).
    imu_sub_ = nh.subscribe(params_.imu_topic, 2000, &TrackingNodelet::imuCallback, this);
  }
  publishBodyTransform();  // before any frame: the SLAM thread sends it later otherwise
  subscribeImages(image_nh, pnh);
  image_thread_ = std::thread([this] {
    // disable() (destructor) wakes the wait at once; the timeout only bounds an idle wait.
    while (image_queue_.isEnabled()) image_queue_.callAvailable(ros::WallDuration(1.0));
  });
}

void TrackingNodelet::logMapFrameSource() const {
  const char* map_frame = params_.map_frame.c_str();
  if (params_.opticalMap()) {
    NODELET_INFO("map frame '%s': the first camera's optical frame (~map_convention optical: z forward, y down)",
                 map_frame);
  } else if (!params_.imu_topic.empty()) {
    NODELET_INFO("map frame '%s': z up along gravity from %s (%.2f s of accelerometer before the initialization), "
                 "x the first camera's heading",
                 map_frame, params_.imu_topic.c_str(), params_.gravity_window_s);
  } else if (!params_.base_frame.empty() && params_.base_frame != params_.body_frame) {
    NODELET_INFO("map frame '%s': the pose of %s when the first image was taken (REP-105; z up for a level robot)",
                 map_frame, params_.base_frame.c_str());
  } else {
    NODELET_INFO("map frame '%s': the first camera in ROS axes (x forward, z up): the map is only as level as "
                 "the first camera (set ~imu_topic or ~base_frame for a level map)",
                 map_frame);
  }
  if (!params_.odom_frame.empty() && !params_.base_frame.empty()) {
    NODELET_INFO("REP-105: publishing %s -> %s (from %s -> %s)", map_frame, params_.odom_frame.c_str(),
                 params_.odom_frame.c_str(), params_.base_frame.c_str());
  } else if (!params_.base_frame.empty()) {
    NODELET_INFO("publishing %s -> %s (the camera under the base frame)", map_frame, params_.base_frame.c_str());
  }
}

void TrackingNodelet::advertise(ros::NodeHandle& pnh) {
  path_.header.frame_id = params_.map_frame;
  pose_pub_ = pnh.advertise<geometry_msgs::PoseStamped>("pose", 10);
  odom_pub_ = pnh.advertise<nav_msgs::Odometry>("odometry", 10);
  path_pub_ = pnh.advertise<nav_msgs::Path>("path", 1, true);
  points_pub_ = pnh.advertise<sensor_msgs::PointCloud2>("points", 2);
  map_points_pub_ = pnh.advertise<sensor_msgs::PointCloud2>("map_points", 1, true);
  status_pub_ = pnh.advertise<vitamin_e::TrackingStatus>("status", 10);
  frame_pub_ = pnh.advertise<vitamin_e::TrackedFrame>("frame", params_.process_all_frames ? 1000 : 5);
  image_transport::ImageTransport private_it(pnh);
  tracking_image_pub_ = private_it.advertise("tracking_image", 1);

  reconfigure_server_ =
      std::make_unique<dynamic_reconfigure::Server<vitamin_e::TrackingConfig>>(reconfigure_mutex_, pnh);
  reconfigure_server_->setCallback([this](vitamin_e::TrackingConfig& c, uint32_t level) { reconfigure(c, level); });
  reset_srv_ = pnh.advertiseService("reset", &TrackingNodelet::resetService, this);
  save_trajectory_srv_ = pnh.advertiseService("save_trajectory", &TrackingNodelet::saveTrajectoryService, this);
  save_map_srv_ = pnh.advertiseService("save_map", &TrackingNodelet::saveMapService, this);
  export_points_srv_ = pnh.advertiseService("export_points", &TrackingNodelet::exportPointsService, this);
}

void TrackingNodelet::startDiagnostics(ros::NodeHandle& nh, ros::NodeHandle& pnh) {
  // Diagnostics are published from their own thread: they never wait for a frame being
  // processed. Every publisher and every subscription but the images' is on the nodelet's
  // single-threaded queue: nodelet::Loader may delete a nodelet inside a callback of one of its
  // queues after the other queue is gone, and roscpp then crashes removing the callbacks of that
  // other queue's publishers (seen with the diagnostics publisher on the multi-threaded queue).
  // The image queue (images and camera_info) is this nodelet's own: shut down and drained in
  // the destructor.
  diagnostics_ = std::make_unique<diagnostic_updater::Updater>(nh, pnh, getName());
  diagnostics_->setHardwareID(params_.camera_frame.empty() ? "camera" : params_.camera_frame);
  diagnostics_->add("vitamin_e tracking", this, &TrackingNodelet::diagnose);
  const double period = params_.diagnostic_period_s;
  diagnostics_thread_ = std::thread([this, period] {
    std::unique_lock<std::mutex> lock(diagnostics_wait_mutex_);
    while (!diagnostics_wake_.wait_for(lock, std::chrono::duration<double>(period),
                                       [this] { return diagnostics_stop_; })) {
      lock.unlock();
      diagnostics_->force_update();
      lock.lock();
    }
  });
}

void TrackingNodelet::checkTransport(ros::NodeHandle& pnh) {
  // The transport is the nodelet's own ~image_transport (image_transport's default reads the
  // manager's private namespace instead).
  const image_transport::TransportHints hints(params_.image_transport, ros::TransportHints(), pnh);
  transport_ = hints.getTransport();
  const auto loadable = it_->getLoadableTransports();
  transport_plugin_ = std::find(loadable.begin(), loadable.end(), "image_transport/" + transport_) != loadable.end() ||
                      std::find(loadable.begin(), loadable.end(), transport_) != loadable.end();
  if (transport_plugin_ || transport_ == "compressed") return;
  std::string names;
  for (const auto& l : loadable) names += (names.empty() ? "" : ", ") + l;
  const std::string why = "~image_transport '" + transport_ + "' is not installed (installed: " + names +
                          "; 'compressed' is decoded here even without its plugin): the nodelet does not start";
  NODELET_FATAL("%s", why.c_str());
  throw std::runtime_error(why);
}

void TrackingNodelet::subscribeImages(ros::NodeHandle& image_nh, ros::NodeHandle& pnh) {
  const image_transport::TransportHints hints(params_.image_transport, ros::TransportHints(), pnh);
  const int queue_size = params_.subscriberQueue();
  const uint32_t queue = static_cast<uint32_t>(queue_size);
  const char* mode = params_.process_all_frames ? "every frame processed: the SLAM queue waits when full"
                                                : "live: the SLAM takes the newest frame, stale frames are dropped";
  if (transport_plugin_) {
    image_sub_ = it_->subscribe("image", queue, &TrackingNodelet::imageCallback, this, hints);
    NODELET_INFO("subscribed to %s (transport %s, queue %d, %s)", image_sub_.getTopic().c_str(), transport_.c_str(),
                 queue_size, mode);
    return;
  }
  // Debian's ROS has no compressed_image_transport: read the CompressedImage topic directly.
  compressed_sub_ = image_nh.subscribe(image_nh.resolveName("image") + "/compressed", queue,
                                       &TrackingNodelet::compressedCallback, this);
  NODELET_INFO("image_transport plugin 'compressed' not installed: subscribed to %s (sensor_msgs/CompressedImage, "
               "decoded with OpenCV; queue %d, %s)",
               compressed_sub_.getTopic().c_str(), queue_size, mode);
}

void TrackingNodelet::createSession(const vitamin_e::camera::Camera& camera) {
  makeSession(camera);
  startSlam();
}

void TrackingNodelet::makeSession(const vitamin_e::camera::Camera& camera) {
  try {
    vitamin_e::pipeline::RunnerOptions runner;
    runner.pipelined = params_.pipelined;
    // A bag gives every frame: its run is reproducible. A live camera's dropped frames make each
    // run its own, and the fresher hand-overs keep the latency lower (docs/PERFORMANCE.md).
    runner.reproducible = params_.process_all_frames;
    runner_ = std::make_unique<vitamin_e::pipeline::SessionRunner>(
        system_config_, camera, params_.session(), runner,
        [this](FrameResult&& result, std::uint64_t ticket) { onResult(std::move(result), ticket); },
        [this](const vitamin_e::pipeline::FramePose& pose, std::uint64_t ticket) { onPose(pose, ticket); });
  } catch (const std::exception& e) {
    throw fatal(std::string("cannot start the SLAM system: ") + e.what());
  }
  NODELET_INFO("camera: %s; %s", camera.describe().c_str(),
               params_.pipelined ? "pipelined: frame k+1 is tracked while frame k is mapped (two threads)"
                                 : "sequential: tracking and mapping on one thread");
  bool localization_only = false;
  {
    std::lock_guard<std::mutex> lock(options_mutex_);
    localization_only = dyn_.localization_only;
  }
  if (loaded_map_) {
    try {
      runner_->system().loadMap(*loaded_map_);
    } catch (const std::exception& e) {
      runner_.reset();
      throw fatal("~load_map '" + params_.load_map + "': " + e.what() +
                  " (nothing is processed: fix the file or the parameter and restart)");
    }
    loaded_map_.reset();
    NODELET_INFO("relocalizing in the loaded map %s%s", params_.load_map.c_str(),
                 localization_only ? " (localization only)" : "");
  }
  runner_->system().setLocalizationOnly(localization_only);
  snapshot_.update(session(), map_alignment_.T_map_w);
  camera_width_ = camera.width();
  camera_height_ = camera.height();
}

void TrackingNodelet::startSlam() {
  // From here on runner_ and the [results] state are the SLAM thread's (the thread's start orders
  // the writes above before its first read).
  slam_thread_ = std::thread([this] { slamLoop(); });
  calibrated_ = true;
  std::lock_guard<std::mutex> lock(stats_mutex_);
  stats_.calibrated = true;
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
  if (runner_ && started_) saveOnShutdown();
}

void TrackingNodelet::saveOnShutdown() {
  // stderr: rosout may be gone at shutdown.
  const auto q = queue_->counts();
  std::fprintf(stderr,
               "[vitamin_e] %zu frames processed, %zu tracked, %d init retries, %d relocalizations, %u segment(s) in "
               "%u map(s), %zu time jump(s); %zu frames dropped by the live queue, %zu still queued at shutdown (not "
               "processed)\n%s",
               session().framesProcessed(), session().framesTracked(), session().initRetries(),
               session().relocalizations(), session().segment(), session().map(), session().timeJumps(), q.dropped,
               q.discarded, session().system().timings().table().c_str());
  std::string message;
  if (!params_.trajectory_file.empty()) {
    saveTrajectory(params_.trajectory_file, &message);
    std::fprintf(stderr, "[vitamin_e] %s\n", message.c_str());
  }
  if (!params_.export_points.empty()) {
    writePoints(mapPointsInMap(), params_.export_points, &message);
    std::fprintf(stderr, "[vitamin_e] %s\n", message.c_str());
  }
  if (!params_.save_map.empty()) {
    if (session().system().localizationOnly()) {
      message = "localization only: the map is unchanged, " + params_.save_map + " not written";
    } else {
      writeMap(session().system().exportMap(), params_.save_map, &message);
    }
    std::fprintf(stderr, "[vitamin_e] %s\n", message.c_str());
  }
}

void TrackingNodelet::cameraInfoCallback(const sensor_msgs::CameraInfoConstPtr& msg) {
  vitamin_e::camera::Camera camera;
  try {
    camera = cameraFromInfo(*msg, rectified_);
  } catch (const std::exception& e) {
    NODELET_ERROR_THROTTLE(5.0, "camera_info rejected: %s", e.what());
    return;
  }
  if (calibrated_) {
    // The calibration is fixed at start-up; a later change is said once.
    if (!params_.calibration_file.empty() || info_change_warned_ || !info_camera_.valid()) return;
    const auto differs = [](double a, double b) { return std::abs(a - b) > 1e-6 * std::max(1.0, std::abs(b)); };
    const bool changed = camera.width() != info_camera_.width() || camera.height() != info_camera_.height() ||
                         differs(camera.fx(), info_camera_.fx()) || differs(camera.fy(), info_camera_.fy()) ||
                         differs(camera.cx(), info_camera_.cx()) || differs(camera.cy(), info_camera_.cy()) ||
                         camera.model() != info_camera_.model() || camera.distortion() != info_camera_.distortion();
    if (changed) {
      info_change_warned_ = true;
      NODELET_WARN("camera_info changed: now %s, the SLAM keeps %s (the calibration is taken once, at start-up: "
                   "restart the tracker to use the new one); said once",
                   camera.describe().c_str(), info_camera_.describe().c_str());
    }
    return;
  }
  try {
    createSession(camera);
    info_camera_ = camera;
  } catch (const std::exception&) {
    // Said by createSession (FATAL); the nodelet stays without a SLAM: nothing is processed.
    info_sub_.shutdown();
    image_sub_.shutdown();
    compressed_sub_.shutdown();
    early_frames_.clear();
    return;
  }
  std::deque<std::pair<cv::Mat, std_msgs::Header>> early;
  early.swap(early_frames_);
  for (auto& [gray, header] : early) enqueue(std::move(gray), header);
}

void TrackingNodelet::imuCallback(const sensor_msgs::ImuConstPtr& msg) {
  const auto& a = msg->linear_acceleration;
  const auto& w = msg->angular_velocity;
  imu_.add(msg->header.stamp.toSec(), Eigen::Vector3d(a.x, a.y, a.z), Eigen::Vector3d(w.x, w.y, w.z),
           msg->header.frame_id);
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
    // Held for the first camera_info (it may come just after its image); older ones are dropped.
    if (early_frames_.size() == kEarlyFrames) {
      early_frames_.pop_front();
      noteRejected();
      NODELET_WARN_THROTTLE(5.0, "image dropped: no calibration yet (set ~calibration_file or publish camera_info)");
    }
    early_frames_.emplace_back(std::move(gray), header);
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
  const bool live = !params_.process_all_frames;
  while (true) {
    // Live and pipelined: the newest frame is taken when a stage can start on it, not held
    // stale in front of a busy one (sequential: at once).
    if (live) runner_->waitUntilNoneWaiting();
    if (!queue_->next(&frame, &command)) break;
    if (command) {
      runner_->flush();  // the command may read or change what the runner's frames change
      command();
      continue;
    }
    if (!frame) continue;  // next() gives a command or a frame; this keeps the check local
    {
      std::lock_guard<std::mutex> lock(stats_mutex_);
      stats_.queue_wait_s.push_back(ros::WallTime::now().toSec() - frame->received_wall);
      while (stats_.queue_wait_s.size() > 200) stats_.queue_wait_s.pop_front();
    }
    // ~debug_frame_delay: the frame is in progress for that long (a slow SLAM, for tests);
    // shutting down ends the wait, and the frame is not processed.
    if (params_.debug_frame_delay_s > 0.0 && !queue_->waitFor(params_.debug_frame_delay_s)) continue;
    processFrame(*frame);
  }
  runner_->flush();  // the frames given to the runner are published, and saved on shutdown
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
  PendingFrame pending;
  {
    std::lock_guard<std::mutex> lock(options_mutex_);
    pending.options = dyn_;
  }
  // Written only here; the runner's threads read it.
  if (runner_->system().localizationOnly() != pending.options.localization_only) {
    runner_->flush();  // switched between two frames of the mapper
    runner_->system().setLocalizationOnly(pending.options.localization_only);
  }
  pending.frame_id =
      !params_.camera_frame.empty() ? params_.camera_frame : (header.frame_id.empty() ? "camera" : header.frame_id);
  const double stamp = header.stamp.toSec();
  const unsigned map_before = session().map();
  const vitamin_e::pipeline::SessionStamp admitted = runner_->admit(stamp);
  if (!admitted.admitted) {
    noteRejected();
    NODELET_ERROR_THROTTLE(2.0, "image dropped: %s", admitted.dropped_why.c_str());
    return;
  }
  if (admitted.time_jump) {
    // The runner is idle (admit emptied it before the jump): its [results] state is ours.
    NODELET_WARN("%s: trajectory segment %u begins in map %u (~time_jump relocalize; ~reset starts a new map)",
                 session().segmentNote().c_str(), session().segment(), session().map());
    if (session().map() != map_before) {
      // Nothing to relocalize in: the session started a new map, with a map frame of its own.
      snapshot_.update(session(), map_alignment_.T_map_w);
      map_alignment_ = MapAlignment{};
    }
    startPath();
  }
  pending.frame = frame;
  pending.start = std::chrono::steady_clock::now();
  const std::uint64_t ticket = next_ticket_++;
  {
    // Before process(): the result may come before it returns.
    std::lock_guard<std::mutex> lock(pending_mutex_);
    pending_.emplace(ticket, std::move(pending));
  }
  bool processed = false;
  std::string why = "shutting down";
  try {
    processed = runner_->process(frame.gray, stamp, stampText(header.stamp.sec, header.stamp.nsec), ticket);
  } catch (const std::exception& e) {
    why = e.what();
  }
  if (!processed) {
    {
      std::lock_guard<std::mutex> lock(pending_mutex_);
      pending_.erase(ticket);
    }
    noteRejected();
    NODELET_ERROR_THROTTLE(2.0, "frame %.9f not processed: %s", stamp, why.c_str());
  }
}

void TrackingNodelet::onResult(FrameResult&& result, std::uint64_t ticket) {
  PendingFrame frame;
  {
    std::lock_guard<std::mutex> lock(pending_mutex_);
    const auto it = pending_.find(ticket);
    if (it == pending_.end()) return;  // cannot happen: every ticket is in pending_ until its result
    frame = std::move(it->second);
    pending_.erase(it);
  }
  const std_msgs::Header& header = frame.frame.header;
  options_ = frame.options;
  frame_id_ = frame.frame_id;
  if (!body_tf_sent_) publishBodyTransform();
  const double ms = vitamin_e::elapsedMs(frame.start);
  if (result.pose_valid && !map_alignment_.fixed) alignMap(result);
  // IMU samples older than any later frame's gravity window (until the map is fixed), or than
  // the rotation check's last interval, are not needed.
  imu_.dropBefore(header.stamp.toSec() - (map_alignment_.fixed ? 2.0 : params_.gravity_window_s + 1.0));
  if (!params_.imu_topic.empty() && !rotation_check_.decided()) checkImuRotation(result);
  snapshot_.update(session(), map_alignment_.T_map_w);
  // Everything published is in the map frame: T_map_c = T_map_w T_w_c, p_map = T_map_w p_w.
  if (map_alignment_.fixed) {
    result.T_w_c = map_alignment_.T_map_w * result.T_w_c;
    for (auto& p : result.points) {
      if (p.has_position) p.p_w = map_alignment_.T_map_w * p.p_w;
    }
  }
  publishResult(result, frame.frame, ms, frame.pose_published);
  previous_pose_valid_ = result.pose_valid;
}

void TrackingNodelet::onPose(const vitamin_e::pipeline::FramePose& pose, std::uint64_t ticket) {
  if (!map_alignment_.fixed) return;  // the map frame is fixed at the first result: the pose goes out with it
  std_msgs::Header header;
  {
    std::lock_guard<std::mutex> lock(pending_mutex_);
    const auto it = pending_.find(ticket);
    if (it == pending_.end()) return;
    it->second.pose_published = true;
    header = it->second.frame.header;
    options_ = it->second.options;
    frame_id_ = it->second.frame_id;
  }
  if (!body_tf_sent_) publishBodyTransform();
  vitamin_e::pipeline::FramePose in_map = pose;
  in_map.T_w_c = map_alignment_.T_map_w * pose.T_w_c;
  publishFramePose(in_map, header);
}

void TrackingNodelet::resetMap(const std::string& why) {
  runner_->reset(why);
  snapshot_.update(session(), map_alignment_.T_map_w);  // the finished segment, in the old map frame
  map_alignment_ = MapAlignment{};
  rotation_check_.restart();
  startPath();
  snapshot_.update(session(), map_alignment_.T_map_w);
}

void TrackingNodelet::startPath() {
  last_map_points_ = ros::Time();
  track_history_.clear();
  previous_pose_valid_ = false;
  rotation_check_.restart();
  path_.poses.clear();
  path_pub_.publish(path_);
  std::lock_guard<std::mutex> lock(stats_mutex_);
  stats_.segment = session().segment();
  stats_.map = session().map();
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
  unsigned segment = 0, map = 0;
  std::string why;
  res.success = runOnSlamThread(
      [&] {
        resetMap("~reset");
        segment = session().segment();
        map = session().map();
      },
      &why);
  if (!res.success) {
    res.message = why;
    return true;
  }
  res.message = "map, tracks, last stamp and path reset; trajectory segment " + std::to_string(segment) +
                " begins in map " + std::to_string(map) + " (earlier segments kept)";
  NODELET_INFO("%s", res.message.c_str());
  return true;
}

bool TrackingNodelet::saveTrajectory(const std::string& path, std::string* message) {
  if (!calibrated_) {
    *message = "no SLAM system yet";
    return false;
  }
  // A copy of the snapshot: the SLAM thread goes on while the file is written.
  const std::vector<vitamin_e::pipeline::TrajectorySegment> all = snapshot_.segments();
  std::size_t poses = 0;
  for (const auto& s : all) poses += s.poses.size();
  const std::string header =
      "T_map_c: camera (optical) in '" + params_.map_frame + "'; each map has its own frame and scale";
  std::string error;
  if (!vitamin_e::pipeline::saveSegmentsTum(all, header, path, &error)) {
    *message = "cannot write trajectory " + path + ": " + error;
    return false;
  }
  *message = "trajectory (" + std::to_string(poses) + " poses in " + std::to_string(all.size()) +
             " segment(s), TUM) written to " + path;
  if (queue_) {
    // Said, so that a caller knows the file is a snapshot of a run still going on.
    const auto q = queue_->counts();
    const std::size_t pending = q.waiting + (q.busy ? 1 : 0) + (runner_ ? runner_->inFlight() : 0);
    if (pending > 0) *message += "; " + std::to_string(pending) + " frame(s) not processed yet";
  }
  return true;
}

std::vector<vitamin_e::pipeline::MapPoint3> TrackingNodelet::mapPointsInMap() const {
  auto points = session().system().mapPoints();
  for (auto& p : points) p.p_w = map_alignment_.T_map_w * p.p_w;
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
  *message =
      "map points (" + std::to_string(points.size()) + " in '" + params_.map_frame + "', PLY) written to " + path;
  return true;
}

bool TrackingNodelet::saveTrajectoryService(vitamin_e::SaveFile::Request& req, vitamin_e::SaveFile::Response& res) {
  auto save = [this](const std::string& path, std::string* message) { return saveTrajectory(path, message); };
  if (answerSaveFile(req, params_.trajectory_file, "trajectory_file", "", &res, save)) {
    NODELET_INFO("%s", res.message.c_str());
  }
  return true;
}

bool TrackingNodelet::saveMapService(vitamin_e::SaveFile::Request& req, vitamin_e::SaveFile::Response& res) {
  // The map is the SLAM thread's: copied there between two frames, written here.
  auto save = [this](const std::string& path, std::string* message) {
    vitamin_e::map::MapFileContents contents;
    if (!runOnSlamThread([&] { contents = session().system().exportMap(); }, message)) return false;
    return writeMap(contents, path, message);
  };
  if (answerSaveFile(req, params_.save_map, "save_map", "", &res, save)) NODELET_INFO("%s", res.message.c_str());
  return true;
}

bool TrackingNodelet::exportPointsService(vitamin_e::SaveFile::Request& req, vitamin_e::SaveFile::Response& res) {
  auto save = [this](const std::string& path, std::string* message) {
    std::vector<vitamin_e::pipeline::MapPoint3> points;
    if (!runOnSlamThread([&] { points = mapPointsInMap(); }, message)) return false;
    return writePoints(points, path, message);
  };
  if (answerSaveFile(req, params_.export_points, "export_points", "", &res, save)) {
    NODELET_INFO("%s", res.message.c_str());
  }
  return true;
}

}  // namespace vitamin_e_ros

PLUGINLIB_EXPORT_CLASS(vitamin_e_ros::TrackingNodelet, nodelet::Nodelet)
