#pragma once
// vitamin_e/TrackingNodelet: images in, SLAM outputs (tf, pose, odometry, path,
// clouds, status, per-frame messages for the mesher) out. A thin layer: every
// estimate comes from pipeline::System; this class only converts and publishes.
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <string>

#include <dynamic_reconfigure/server.h>
#include <image_transport/image_transport.h>
#include <nodelet/nodelet.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <std_srvs/Trigger.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_broadcaster.h>
#include <tf2_ros/transform_listener.h>
#include <nav_msgs/Path.h>

#include "vitamin_e/SaveFile.h"
#include "vitamin_e/TrackingConfig.h"
#include "vitamin_e/pipeline/system.h"

namespace vitamin_e_ros {

class TrackingNodelet : public nodelet::Nodelet {
 public:
  TrackingNodelet() = default;
  ~TrackingNodelet() override;

 private:
  void onInit() override;
  bool createSystem(const vitamin_e::camera::Camera& camera);
  void imageCallback(const sensor_msgs::ImageConstPtr& msg);
  void cameraInfoCallback(const sensor_msgs::CameraInfoConstPtr& msg);
  void reconfigure(vitamin_e::TrackingConfig& config, uint32_t level);
  bool resetService(std_srvs::Trigger::Request& req, std_srvs::Trigger::Response& res);
  bool saveTrajectoryService(vitamin_e::SaveFile::Request& req, vitamin_e::SaveFile::Response& res);
  bool saveMapService(vitamin_e::SaveFile::Request& req, vitamin_e::SaveFile::Response& res);
  bool exportPointsService(vitamin_e::SaveFile::Request& req, vitamin_e::SaveFile::Response& res);
  bool saveTrajectory(const std::string& path, std::string* message);
  bool saveMap(const std::string& path, std::string* message);       // the map file (~load_map reads it)
  bool exportPoints(const std::string& path, std::string* message);  // the map points as PLY

  // Publishing (tracking_publish.cpp); called with mutex_ held.
  void publishResult(const vitamin_e::pipeline::FrameResult& result, const std_msgs::Header& header,
                     const cv::Mat& gray, double ms);
  void publishPose(const vitamin_e::pipeline::FrameResult& result, const std_msgs::Header& header);
  void publishTf(const Eigen::Isometry3d& T_w_c, const ros::Time& stamp);
  void publishPoints(const vitamin_e::pipeline::FrameResult& result, const std_msgs::Header& header);
  void publishFrame(const vitamin_e::pipeline::FrameResult& result, const std_msgs::Header& header);
  void publishMapPoints(const ros::Time& stamp);
  void publishTrackingImage(const vitamin_e::pipeline::FrameResult& result, const std_msgs::Header& header,
                            const cv::Mat& gray);

  // Parameters (read once in onInit).
  std::string map_frame_ = "map";
  std::string camera_frame_;  // empty: the image's frame_id
  std::string odom_frame_;
  std::string base_frame_;
  std::string trajectory_file_;
  std::string export_points_;  // PLY of the map points, written on shutdown (~export_points; ~map_file before)
  std::string load_map_;       // map file loaded at start-up
  std::string save_map_;       // map file written on shutdown (not in localization-only mode)
  std::unique_ptr<vitamin_e::map::MapFileContents> loaded_map_;  // ~load_map, until the system takes it
  bool process_all_frames_ = false;

  std::mutex mutex_;  // guards everything below (callbacks, services, reconfigure)
  vitamin_e::TrackingConfig dyn_;
  vitamin_e::pipeline::SystemConfig system_config_;
  std::unique_ptr<vitamin_e::pipeline::System> system_;
  bool have_last_stamp_ = false;
  ros::Time last_stamp_;
  ros::Time last_map_points_;
  std::string frame_id_;  // camera frame in use
  nav_msgs::Path path_;
  std::map<std::uint64_t, std::deque<cv::Point2f>> track_history_;

  std::unique_ptr<image_transport::ImageTransport> it_;
  image_transport::Subscriber image_sub_;
  ros::Subscriber info_sub_;
  ros::Publisher pose_pub_, odom_pub_, path_pub_, points_pub_, map_points_pub_, status_pub_, frame_pub_;
  image_transport::Publisher tracking_image_pub_;
  ros::ServiceServer reset_srv_, save_trajectory_srv_, save_map_srv_, export_points_srv_;
  std::unique_ptr<dynamic_reconfigure::Server<vitamin_e::TrackingConfig>> reconfigure_server_;
  boost::recursive_mutex reconfigure_mutex_;
  std::unique_ptr<tf2_ros::TransformBroadcaster> tf_broadcaster_;
  std::unique_ptr<tf2_ros::Buffer> tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;
};

}  // namespace vitamin_e_ros
