#pragma once
// vitamin_e/TrackingNodelet: images in, SLAM outputs (tf, pose, odometry, path, clouds,
// status, diagnostics, per-frame messages for the mesher) out. ROS wiring only: the
// parameters come from readTrackingParams (tracking_params.h), every estimate, the stamp
// order and the trajectory segments from pipeline::Session; this class converts,
// re-expresses in the map frame (map_frame.h) and publishes.
//
// Threads:
//   image thread   own callback queue (image_queue_): camera_info (calibration, starts the
//                  SLAM thread), then converts each image and pushes it into queue_ (live:
//                  newest only; ~process_all_frames: blocks when full)
//   SLAM thread    takes the frames (and the commands the services post) from queue_, checks
//                  their stamps and hands them to runner_ (a pipeline::SessionRunner)
//   results        where runner_ delivers the results (onResult) and everything marked
//                  [results] below lives: the SLAM thread itself (sequential), or the
//                  runner's mapping thread (~pipelined: frame k+1 is tracked on the runner's
//                  tracking thread while frame k is mapped). The SLAM thread touches
//                  [results] state only while the runner is idle: before a command it
//                  flushes the runner, and a stamp going back empties it (admit)
//   nodelet queue  (single-threaded) IMU, services, dynamic_reconfigure: they
//                  never wait for a frame being processed; ~save_trajectory reads a snapshot,
//                  ~reset / ~save_map / ~export_points run on the SLAM thread between two
//                  frames (ahead of the waiting ones, after the runner's frames) and wait for that
//   diagnostics    own thread, reads the statistics and the queue's counts
// Shutdown (destructor): diagnostics stopped, queue closed, image subscriptions shut down,
// image thread joined, the SLAM thread finishes the runner's frames and is joined, files saved; only then the publishers go.
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <utility>

#include <diagnostic_updater/diagnostic_updater.h>
#include <dynamic_reconfigure/server.h>
#include <geometry_msgs/PoseStamped.h>
#include <image_transport/image_transport.h>
#include <nav_msgs/Path.h>
#include <nodelet/nodelet.h>
#include <ros/callback_queue.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/Imu.h>
#include <std_srvs/Trigger.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <tf2_ros/transform_broadcaster.h>
#include <tf2_ros/transform_listener.h>

#include "trajectory_snapshot.h"
#include "vitamin_e/SaveFile.h"
#include "vitamin_e/TrackingConfig.h"
#include "vitamin_e/pipeline/dense_input.h"
#include "vitamin_e/pipeline/session.h"
#include "vitamin_e/pipeline/session_runner.h"
#include "vitamin_e/ros/imu_buffer.h"
#include "vitamin_e/ros/map_frame.h"
#include "vitamin_e/ros/slam_queue.h"
#include "vitamin_e/ros/tracking_params.h"

namespace vitamin_e_ros {

class TrackingNodelet : public nodelet::Nodelet {
 public:
  TrackingNodelet() = default;
  ~TrackingNodelet() override;

 private:
  // A converted image waiting for the SLAM thread.
  struct QueuedFrame {
    cv::Mat gray;
    std_msgs::Header header;
    double received_wall = 0.0;  // when the callback queued it (queue wait in the diagnostics)
  };
  // A frame given to runner_, until its result comes: what publishing it needs.
  struct PendingFrame {
    QueuedFrame frame;
    vitamin_e::TrackingConfig options;  // the reconfigure values as of the frame
    std::string frame_id;               // its camera frame
    std::chrono::steady_clock::time_point start;
    bool pose_published = false;  // its pose went out before the result (onPose)
  };

  // onInit throws std::runtime_error (after a FATAL saying why) when the nodelet cannot run:
  // nodelet::Loader then unloads it and `nodelet load` (or tracking_node) exits non-zero.
  void onInit() override;
  std::runtime_error fatal(const std::string& why) const;  // NODELET_FATAL, then the exception to throw
  // ~parameters and the files they name (config, calibration, map), read and logged.
  TrackingFiles loadConfiguration(ros::NodeHandle& pnh);
  // camera_info, IMU and images, and the images' callback thread: last, when everything runs.
  void subscribe(ros::NodeHandle& nh, ros::NodeHandle& image_nh, ros::NodeHandle& pnh);
  void logMapFrameSource() const;
  void advertise(ros::NodeHandle& pnh);
  void startDiagnostics(ros::NodeHandle& nh, ros::NodeHandle& pnh);
  // ~image_transport: a plugin, or compressed (decoded here); throws (after a FATAL) otherwise.
  void checkTransport(ros::NodeHandle& pnh);
  void subscribeImages(ros::NodeHandle& image_nh, ros::NodeHandle& pnh);
  // makeSession, then startSlam.
  void createSession(const vitamin_e::camera::Camera& camera);
  // Builds runner_ (and loads ~load_map). Throws std::runtime_error (after a FATAL) when it
  // cannot.
  void makeSession(const vitamin_e::camera::Camera& camera);
  void startSlam();  // the SLAM thread, on runner_
  void imageCallback(const sensor_msgs::ImageConstPtr& msg);
  void compressedCallback(const sensor_msgs::CompressedImageConstPtr& msg);
  // The image callbacks' end: the calibration's size checked, the frame queued.
  void enqueue(cv::Mat gray, const std_msgs::Header& header);
  void cameraInfoCallback(const sensor_msgs::CameraInfoConstPtr& msg);
  void imuCallback(const sensor_msgs::ImuConstPtr& msg);
  void reconfigure(vitamin_e::TrackingConfig& config, uint32_t level);
  bool resetService(std_srvs::Trigger::Request& req, std_srvs::Trigger::Response& res);
  bool saveTrajectoryService(vitamin_e::SaveFile::Request& req, vitamin_e::SaveFile::Response& res);
  bool saveMapService(vitamin_e::SaveFile::Request& req, vitamin_e::SaveFile::Response& res);
  bool exportPointsService(vitamin_e::SaveFile::Request& req, vitamin_e::SaveFile::Response& res);
  // The trajectory from the snapshot (any thread).
  bool saveTrajectory(const std::string& path, std::string* message);
  // The session's map points in the map frame: [results] state.
  std::vector<vitamin_e::pipeline::MapPoint3> mapPointsInMap() const;
  bool writeMap(const vitamin_e::map::MapFileContents& contents, const std::string& path, std::string* message);
  bool writePoints(const std::vector<vitamin_e::pipeline::MapPoint3>& points, const std::string& path,
                   std::string* message);
  // The files of the parameters, written after the SLAM thread has ended (destructor).
  void saveOnShutdown();
  // Runs `work` on the SLAM thread before its next frame and waits for it (services). False
  // (and *why) when there is no SLAM thread or it is shutting down.
  bool runOnSlamThread(const std::function<void()>& work, std::string* why);
  // Closes the queue, stops the image thread and joins the SLAM thread (destructor).
  void stopThreads();

  // The SLAM thread.
  void slamLoop();
  // Stamp checks and time jumps (the session), then the frame to runner_.
  void processFrame(const QueuedFrame& frame);
  // [results] A frame's result: map frame, publishing.
  void onResult(vitamin_e::pipeline::FrameResult&& result, std::uint64_t ticket);
  // A tracked frame's pose before its map work: published at once (pose, odometry, path, tf),
  // so that a keyframe's window BA is not in the pose's latency. [results]
  void onPose(const vitamin_e::pipeline::FramePose& pose, std::uint64_t ticket);
  // The session: [results] state (the SLAM thread reads it only while runner_ is idle).
  const vitamin_e::pipeline::Session& session() const { return runner_->session(); }
  // A new map (~reset; runner_ idle): the session's next segment, the map frame and the path
  // start over.
  void resetMap(const std::string& why);
  // A new segment began (a time jump, or a reset): the path and the track trails start over.
  void startPath();

  // The map frame (tracking_map_frame.cpp); SLAM thread.
  void alignMap(const vitamin_e::pipeline::FrameResult& result);
  bool imuToCamera(Eigen::Matrix3d* R_c_imu, std::string* source, std::string* why);
  // The camera's turns against the gyroscope's (the camera -> IMU rotation), once enough
  // rotation was seen: a WARN when they disagree.
  void checkImuRotation(const vitamin_e::pipeline::FrameResult& result);
  // The camera's mounting on ~base_frame (static): from the calibration when ~base_frame is
  // ~body_frame, else looked up once on tf (waiting at most timeout_s).
  bool cameraToBase(Eigen::Isometry3d* T_c_base, std::string* why, double timeout_s = 0.0);
  void publishBodyTransform();

  // Publishing (tracking_publish.cpp); SLAM thread. `result` is in the map frame.
  // pose_published: the frame's pose went out already (onPose), the rest of the result goes now.
  void publishResult(const vitamin_e::pipeline::FrameResult& result, const QueuedFrame& frame, double ms,
                     bool pose_published);
  // pose, odometry, path and tf of a frame (pose in the map frame), the latency noted.
  void publishFramePose(const vitamin_e::pipeline::FramePose& pose, const std_msgs::Header& header);
  void publishPose(const vitamin_e::pipeline::FramePose& pose, const std_msgs::Header& header);
  void publishPath(const geometry_msgs::PoseStampedConstPtr& stamped);
  void publishTf(const Eigen::Isometry3d& T_map_c, const ros::Time& stamp);
  void publishPoints(const vitamin_e::pipeline::FrameResult& result, const std_msgs::Header& header);
  void publishFrame(const vitamin_e::fusion::DenseFrame& frame, const std_msgs::Header& header);
  void publishMapPoints(const ros::Time& stamp);
  void publishTrackingImage(const vitamin_e::pipeline::FrameResult& result, const std_msgs::Header& header,
                            const cv::Mat& gray);

  // Diagnostics (tracking_diagnostics.cpp): own mutex, never waits for a frame.
  struct Stats {
    std::deque<double> received_wall, processed_wall;  // wall times over the last window
    std::deque<double> latency_s;                      // image stamp -> published pose
    std::deque<double> queue_wait_s;                   // queued -> taken by the SLAM thread
    double last_stamp = 0.0, period_s = 0.0;           // input period from the stamps (median)
    std::deque<double> stamp_deltas;
    std::size_t received = 0, processed = 0, rejected = 0, gap_dropped = 0;
    int state = -1;  // vitamin_e::TrackingStatus state, -1: none yet
    std::string state_name, message;
    std::size_t tracked = 0, mapped = 0, map_size = 0;
    int init_retries = 0;
    unsigned segment = 1, map = 1;
    bool calibrated = false;
  };
  void noteReceived(const ros::Time& stamp);
  void noteRejected();
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status);

  // Parameters (read once in onInit, constant afterwards), and what they load.
  TrackingParams params_;
  vitamin_e::pipeline::SystemConfig system_config_;
  Eigen::Isometry3d T_b_c_ = Eigen::Isometry3d::Identity();      // ~calibration_file's T_BS
  std::unique_ptr<vitamin_e::map::MapFileContents> loaded_map_;  // ~load_map, until the session takes it
  bool rectified_ = false;
  std::string transport_ = "raw";
  bool transport_plugin_ = false;  // transport_ has an image_transport plugin (else compressed, decoded here)

  // The camera's size for the callbacks' check, set before calibrated_.
  int camera_width_ = 0, camera_height_ = 0;
  std::atomic<bool> calibrated_{false};  // runner_ exists and the SLAM thread runs
  bool started_ = false;                 // onInit completed (else nothing is saved at unload)
  // [image thread] The camera taken from camera_info, and whether a later one differed.
  vitamin_e::camera::Camera info_camera_;
  bool info_change_warned_ = false;
  // [image thread] Images that came before the first camera_info (over two connections a bag's
  // first image may overtake its camera_info): handed to the SLAM once it arrives, the newest
  // kEarlyFrames of them, so that the first frame does not depend on that race.
  static constexpr std::size_t kEarlyFrames = 10;
  std::deque<std::pair<cv::Mat, std_msgs::Header>> early_frames_;

  // Reconfigure writes, the SLAM thread copies per frame (never held while processing).
  std::mutex options_mutex_;
  vitamin_e::TrackingConfig dyn_;

  // The SLAM thread's (the destructor's after the join).
  std::unique_ptr<vitamin_e::pipeline::SessionRunner> runner_;
  std::uint64_t next_ticket_ = 0;
  // The frames in runner_, by ticket (SLAM thread and results).
  std::mutex pending_mutex_;
  std::map<std::uint64_t, PendingFrame> pending_;
  // [results] state: see Threads (the destructor's after the join).
  vitamin_e::TrackingConfig options_;  // dyn_ as of the current result's frame
  ros::Time last_map_points_;
  std::string frame_id_;  // camera frame in use
  nav_msgs::Path path_;
  std::map<std::uint64_t, std::deque<cv::Point2f>> track_history_;
  // The mesher's input (~frame): every result goes through it, for the map's scale corrections.
  vitamin_e::pipeline::DenseInput dense_input_;
  unsigned dense_input_map_ = 1;
  bool previous_pose_valid_ = false;  // the frame before had a pose (the odometry's step exists)
  // The map frame of the session's current map: T_map_w once its first pose fixed it (alignMap).
  struct MapAlignment {
    bool fixed = false;
    Eigen::Isometry3d T_map_w = Eigen::Isometry3d::Identity();
    std::string description;  // how it was fixed, for the log
  };
  MapAlignment map_alignment_;
  bool have_T_c_base_ = false;
  Eigen::Isometry3d T_c_base_ = Eigen::Isometry3d::Identity();
  bool body_tf_sent_ = false;
  ImuRotationCheck rotation_check_;  // the camera -> IMU rotation against the camera's turns

  TrajectorySnapshot snapshot_;  // ~save_trajectory's copy (own mutex)
  ImuBuffer imu_;                // ~imu_topic's samples (own mutex)

  std::mutex stats_mutex_;
  Stats stats_;

  std::unique_ptr<SlamQueue<QueuedFrame>> queue_;
  std::thread slam_thread_;
  // The image subscriptions' own callback queue and thread: a callback blocked on a full
  // queue_ (bag mode) holds up nothing else. Declared before the subscribers (outlives them).
  ros::CallbackQueue image_queue_;
  std::thread image_thread_;

  std::unique_ptr<image_transport::ImageTransport> it_;
  image_transport::Subscriber image_sub_;
  ros::Subscriber compressed_sub_, info_sub_, imu_sub_;
  ros::Publisher pose_pub_, odom_pub_, path_pub_, points_pub_, map_points_pub_, status_pub_, frame_pub_;
  image_transport::Publisher tracking_image_pub_;
  ros::ServiceServer reset_srv_, save_trajectory_srv_, save_map_srv_, export_points_srv_;
  std::unique_ptr<dynamic_reconfigure::Server<vitamin_e::TrackingConfig>> reconfigure_server_;
  boost::recursive_mutex reconfigure_mutex_;
  std::unique_ptr<tf2_ros::TransformBroadcaster> tf_broadcaster_;
  std::unique_ptr<tf2_ros::StaticTransformBroadcaster> static_broadcaster_;
  std::unique_ptr<tf2_ros::Buffer> tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;
  std::unique_ptr<diagnostic_updater::Updater> diagnostics_;
  // Its own thread (a ros::WallTimer crashed in roscpp's TimerManager when the nodelet unloaded
  // from a nodelet::Loader): wakes every ~diagnostic_period, stopped first in the destructor.
  std::thread diagnostics_thread_;
  std::mutex diagnostics_wait_mutex_;
  std::condition_variable diagnostics_wake_;
  bool diagnostics_stop_ = false;
};

}  // namespace vitamin_e_ros
