#pragma once
// vitamin_e/TrackingNodelet: images in, SLAM outputs (tf, pose, odometry, path,
// clouds, status, diagnostics, per-frame messages for the mesher) out. A thin
// layer: every estimate comes from pipeline::System; this class converts,
// re-expresses in the map frame (map_frame.h) and publishes.
//
// Threads (issue 15, item 8):
//   image thread   own callback queue (image_queue_): camera_info (calibration, starts the
//                  SLAM thread), then converts each image and pushes it into queue_ (live:
//                  newest only; ~process_all_frames: blocks when full)
//   SLAM thread    owns system_ and everything marked [SLAM] below: takes the frames (and
//                  the commands the services post) from queue_, runs the SLAM, publishes
//   nodelet queue  (single-threaded) IMU, services, dynamic_reconfigure: they
//                  never wait for a frame being processed; ~save_trajectory reads a snapshot,
//                  ~reset / ~save_map / ~export_points run on the SLAM thread between two
//                  frames (ahead of the waiting ones) and wait for that
//   diagnostics    own thread, reads the statistics and the queue's counts
// Shutdown (destructor): diagnostics stopped, queue closed, image subscriptions shut down,
// image thread and SLAM thread joined, files saved; only then the publishers go.
#include <atomic>
#include <condition_variable>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

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

#include "vitamin_e/SaveFile.h"
#include "vitamin_e/TrackingConfig.h"
#include "vitamin_e/pipeline/dense_input.h"
#include "vitamin_e/pipeline/system.h"
#include "vitamin_e/ros/map_frame.h"
#include "vitamin_e/ros/slam_queue.h"
#include "vitamin_e/ros/trajectory_segments.h"

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

  void onInit() override;
  bool readFrameParameters(ros::NodeHandle& pnh);
  bool subscribeImages(ros::NodeHandle& image_nh, ros::NodeHandle& pnh, int queue_size);
  // Builds system_ (and loads ~load_map), then starts the SLAM thread.
  bool createSystem(const vitamin_e::camera::Camera& camera);
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
  // The map file / the map points as PLY, from system_: after the SLAM thread has ended.
  bool saveMap(const std::string& path, std::string* message);
  bool exportPoints(const std::string& path, std::string* message);
  // system_'s map points in the map frame: on the SLAM thread (or after it has ended).
  std::vector<vitamin_e::pipeline::MapPoint3> mapPointsInMap() const;
  bool writeMap(const vitamin_e::map::MapFileContents& contents, const std::string& path, std::string* message);
  bool writePoints(const std::vector<vitamin_e::pipeline::MapPoint3>& points, const std::string& path,
                   std::string* message);
  // Runs `work` on the SLAM thread before its next frame and waits for it (services). False
  // (and *why) when there is no SLAM thread or it is shutting down.
  bool runOnSlamThread(const std::function<void()>& work, std::string* why);
  // Closes the queue, stops the image thread and joins the SLAM thread (destructor).
  void stopThreads();

  // The SLAM thread (all [SLAM] state).
  void slamLoop();
  // Stamp checks, time jumps, SLAM, map frame, publishing.
  void processFrame(const QueuedFrame& frame);
  // Ends the current SLAM run (its poses become a finished segment) and starts a fresh one:
  // no map, no last stamp, an empty path.
  void startSegment(const std::string& why);
  std::string segmentNote() const;
  // The services' copy of the trajectory, after every frame and segment change.
  void updateSnapshot();

  // The map frame (tracking_map_frame.cpp); SLAM thread.
  void alignMap(const vitamin_e::pipeline::FrameResult& result);
  bool imuToCamera(Eigen::Matrix3d* R_c_imu, std::string* why);
  // The camera's mounting on ~base_frame (static): from the calibration when ~base_frame is
  // ~body_frame, else looked up once on tf (waiting at most timeout_s).
  bool cameraToBase(Eigen::Isometry3d* T_c_base, std::string* why, double timeout_s = 0.0);
  void publishBodyTransform();

  // Publishing (tracking_publish.cpp); SLAM thread. `result` is in the map frame.
  void publishResult(const vitamin_e::pipeline::FrameResult& result, const QueuedFrame& frame, double ms);
  void publishPose(const vitamin_e::pipeline::FrameResult& result, const std_msgs::Header& header);
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
    unsigned segment = 1;
    bool calibrated = false;
  };
  void noteReceived(const ros::Time& stamp);
  void noteRejected();
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status);

  // Parameters (read once in onInit, constant afterwards).
  std::string map_frame_ = "map";
  std::string camera_frame_;  // empty: the image's frame_id
  std::string odom_frame_;
  std::string base_frame_;
  std::string body_frame_;  // frame of the calibration's T_BS (camera in body/IMU)
  std::string imu_topic_;
  std::string trajectory_file_;
  std::string transport_ = "raw";
  std::string export_points_;  // PLY of the map points, written on shutdown (~export_points; ~map_file before)
  std::string load_map_;       // map file loaded at start-up
  std::string save_map_;       // map file written on shutdown (not in localization-only mode)
  std::unique_ptr<vitamin_e::map::MapFileContents> loaded_map_;  // ~load_map, until the system takes it
  bool process_all_frames_ = false;
  bool optical_map_ = false;  // ~map_convention: optical (the core's world frame)
  double gravity_window_s_ = 1.0;
  bool reset_on_time_jump_ = true;
  double time_jump_threshold_s_ = 1.0;
  double debug_frame_delay_s_ = 0.0;  // ~debug_frame_delay: each frame held this long (tests)
  bool rectified_ = false;
  bool have_calibration_file_ = false;
  Eigen::Isometry3d T_b_c_ = Eigen::Isometry3d::Identity();  // from ~calibration_file

  // The camera's size for the callbacks' check, set before calibrated_.
  int camera_width_ = 0, camera_height_ = 0;
  std::atomic<bool> calibrated_{false};  // system_ exists and the SLAM thread runs

  // Reconfigure writes, the SLAM thread copies per frame (never held while processing).
  std::mutex options_mutex_;
  vitamin_e::TrackingConfig dyn_;

  // [SLAM] state: the SLAM thread's alone once it runs (the destructor's after the join).
  vitamin_e::TrackingConfig options_;  // dyn_ as of the current frame
  vitamin_e::pipeline::SystemConfig system_config_;
  vitamin_e::camera::Camera camera_;
  std::unique_ptr<vitamin_e::pipeline::System> system_;
  bool have_last_stamp_ = false;
  ros::Time last_stamp_;
  ros::Time last_map_points_;
  std::string frame_id_;  // camera frame in use
  nav_msgs::Path path_;
  std::map<std::uint64_t, std::deque<cv::Point2f>> track_history_;
  std::string segment_note_ = "start";
  unsigned segment_ = 1;
  // The mesher's input (~frame): every result goes through it, for the map's scale corrections.
  vitamin_e::pipeline::DenseInput dense_input_;
  unsigned dense_input_segment_ = 1;
  std::size_t finished_processed_ = 0, finished_tracked_ = 0;
  int finished_retries_ = 0, finished_relocalizations_ = 0;
  // The map frame of the current segment: T_map_w once the first pose exists.
  bool have_map_ = false;
  Eigen::Isometry3d T_map_w_ = Eigen::Isometry3d::Identity();
  std::string map_description_;
  bool have_T_c_base_ = false;
  Eigen::Isometry3d T_c_base_ = Eigen::Isometry3d::Identity();
  bool body_tf_sent_ = false;

  // What ~save_trajectory reads: the finished segments (map frame) and the current one's
  // poses in the core's world with its T_map_w. The SLAM thread appends per frame.
  struct TrajectorySnapshot {
    std::vector<TrajectorySegment> finished;
    std::vector<vitamin_e::pipeline::TrajectoryEntry> current;
    Eigen::Isometry3d T_map_w = Eigen::Isometry3d::Identity();
    std::string note;
  };
  std::mutex snapshot_mutex_;
  TrajectorySnapshot snapshot_;

  std::mutex imu_mutex_;  // the accelerometer window (IMU callbacks run beside the SLAM)
  GravityWindow gravity_;
  std::string imu_frame_;
  std::size_t imu_samples_ = 0;

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
