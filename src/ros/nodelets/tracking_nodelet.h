#pragma once
// vitamin_e/TrackingNodelet: images in, SLAM outputs (tf, pose, odometry, path,
// clouds, status, diagnostics, per-frame messages for the mesher) out. A thin
// layer: every estimate comes from pipeline::System; this class converts,
// re-expresses in the map frame (map_frame.h) and publishes.
#include <condition_variable>
#include <deque>
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
#include "vitamin_e/pipeline/system.h"
#include "vitamin_e/ros/map_frame.h"
#include "vitamin_e/ros/trajectory_segments.h"

namespace vitamin_e_ros {

class TrackingNodelet : public nodelet::Nodelet {
 public:
  TrackingNodelet() = default;
  ~TrackingNodelet() override;

 private:
  void onInit() override;
  bool readFrameParameters(ros::NodeHandle& pnh);
  bool subscribeImages(ros::NodeHandle& nh, ros::NodeHandle& pnh, int queue_size);
  bool createSystem(const vitamin_e::camera::Camera& camera);
  void imageCallback(const sensor_msgs::ImageConstPtr& msg);
  void compressedCallback(const sensor_msgs::CompressedImageConstPtr& msg);
  void cameraInfoCallback(const sensor_msgs::CameraInfoConstPtr& msg);
  void imuCallback(const sensor_msgs::ImuConstPtr& msg);
  // Everything after the decoding: checks, time jumps, SLAM, publishing (takes mutex_).
  void processFrame(const cv::Mat& gray, const std_msgs::Header& header);
  void reconfigure(vitamin_e::TrackingConfig& config, uint32_t level);
  bool resetService(std_srvs::Trigger::Request& req, std_srvs::Trigger::Response& res);
  bool saveTrajectoryService(vitamin_e::SaveFile::Request& req, vitamin_e::SaveFile::Response& res);
  bool saveMapService(vitamin_e::SaveFile::Request& req, vitamin_e::SaveFile::Response& res);
  bool exportPointsService(vitamin_e::SaveFile::Request& req, vitamin_e::SaveFile::Response& res);
  bool saveTrajectory(const std::string& path, std::string* message);
  bool saveMap(const std::string& path, std::string* message);       // the map file (~load_map reads it)
  bool exportPoints(const std::string& path, std::string* message);  // the map points as PLY
  // Ends the current SLAM run (its poses become a finished segment) and starts a fresh one:
  // no map, no last stamp, an empty path (mutex_ held).
  void startSegment(const std::string& why);
  // Poses of the finished segments and the current one, in the map frame (mutex_ held).
  std::vector<TrajectorySegment> segments() const;
  std::string segmentNote() const;

  // The map frame (tracking_map_frame.cpp); mutex_ held.
  void alignMap(const vitamin_e::pipeline::FrameResult& result);
  bool imuToCamera(Eigen::Matrix3d* R_c_imu, std::string* why);
  // The camera's mounting on ~base_frame (static): from the calibration when ~base_frame is
  // ~body_frame, else looked up once on tf (waiting at most timeout_s).
  bool cameraToBase(Eigen::Isometry3d* T_c_base, std::string* why, double timeout_s = 0.0);
  void publishBodyTransform();

  // Publishing (tracking_publish.cpp); mutex_ held. `result` is in the map frame.
  void publishResult(const vitamin_e::pipeline::FrameResult& result, const std_msgs::Header& header,
                     const cv::Mat& gray, double ms);
  void publishPose(const vitamin_e::pipeline::FrameResult& result, const std_msgs::Header& header);
  void publishPath(const geometry_msgs::PoseStampedConstPtr& stamped);
  void publishTf(const Eigen::Isometry3d& T_map_c, const ros::Time& stamp);
  void publishPoints(const vitamin_e::pipeline::FrameResult& result, const std_msgs::Header& header);
  void publishFrame(const vitamin_e::pipeline::FrameResult& result, const std_msgs::Header& header);
  void publishMapPoints(const ros::Time& stamp);
  void publishTrackingImage(const vitamin_e::pipeline::FrameResult& result, const std_msgs::Header& header,
                            const cv::Mat& gray);

  // Diagnostics (tracking_diagnostics.cpp): own mutex, never waits for a frame.
  struct Stats {
    std::deque<double> received_wall, processed_wall;  // wall times over the last window
    std::deque<double> latency_s;                      // image stamp -> published pose
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

  // Parameters (read once in onInit).
  std::string map_frame_ = "map";
  std::string camera_frame_;  // empty: the image's frame_id
  std::string odom_frame_;
  std::string base_frame_;
  std::string body_frame_;    // frame of the calibration's T_BS (camera in body/IMU)
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
  bool rectified_ = false;
  bool have_calibration_file_ = false;
  Eigen::Isometry3d T_b_c_ = Eigen::Isometry3d::Identity();  // from ~calibration_file

  std::mutex mutex_;  // guards everything below (callbacks, services, reconfigure)
  vitamin_e::TrackingConfig dyn_;
  vitamin_e::pipeline::SystemConfig system_config_;
  vitamin_e::camera::Camera camera_;
  std::unique_ptr<vitamin_e::pipeline::System> system_;
  bool have_last_stamp_ = false;
  ros::Time last_stamp_;
  ros::Time last_map_points_;
  std::string frame_id_;  // camera frame in use
  nav_msgs::Path path_;
  std::map<std::uint64_t, std::deque<cv::Point2f>> track_history_;
  // Segments: one per SLAM run; the current one is system_'s trajectory.
  std::vector<TrajectorySegment> finished_;
  std::string segment_note_ = "start";
  unsigned segment_ = 1;
  std::size_t finished_processed_ = 0, finished_tracked_ = 0;
  int finished_retries_ = 0, finished_relocalizations_ = 0;
  // The map frame of the current segment: T_map_w once the first pose exists.
  bool have_map_ = false;
  Eigen::Isometry3d T_map_w_ = Eigen::Isometry3d::Identity();
  std::string map_description_;
  bool have_T_c_base_ = false;
  Eigen::Isometry3d T_c_base_ = Eigen::Isometry3d::Identity();
  bool body_tf_sent_ = false;

  std::mutex imu_mutex_;  // the accelerometer window (IMU callbacks run beside the SLAM)
  GravityWindow gravity_;
  std::string imu_frame_;
  std::size_t imu_samples_ = 0;

  std::mutex stats_mutex_;
  Stats stats_;

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
