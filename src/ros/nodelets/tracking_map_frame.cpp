// TrackingNodelet: the map frame of a SLAM run (see vitamin_e/ros/map_frame.h), fixed at its
// first pose. The core's world is the first reference camera, so T_w_c0 = identity below.
#include <cstdio>

#include <geometry_msgs/TransformStamped.h>

#include "tracking_nodelet.h"
#include "vitamin_e/ros/conversions.h"

namespace vitamin_e_ros {

void TrackingNodelet::alignMap(const vitamin_e::pipeline::FrameResult& result) {
  const Eigen::Isometry3d T_w_c0 = Eigen::Isometry3d::Identity();
  have_map_ = true;
  if (optical_map_) {
    T_map_w_ = Eigen::Isometry3d::Identity();
    map_description_ = "map = the first camera's optical frame";
    return;
  }
  std::string why_not;
  if (!imu_topic_.empty()) {
    Eigen::Matrix3d R_c_imu;
    if (imuToCamera(&R_c_imu, &why_not)) {
      GravityWindow::Estimate e;
      std::size_t received = 0;
      {
        const auto& trajectory = system_->trajectory();
        std::lock_guard<std::mutex> lock(imu_mutex_);
        received = imu_samples_;
        e = gravity_.upInWorld(
            result.timestamp, gravity_window_s_, [&](double t) { return orientationAt(trajectory, t); }, R_c_imu);
      }
      if (e.ok) {
        T_map_w_ = mapFromUp(e.up_w, T_w_c0);
        char text[256];
        std::snprintf(text, sizeof(text),
                      "map z up from gravity (%s: %d samples over %.2f s before the initialization, |f| %.2f m/s^2), "
                      "x the first camera's heading",
                      imu_topic_.c_str(), e.samples, e.span_s, e.magnitude);
        map_description_ = text;
        NODELET_INFO("segment %u: %s", segment_, text);
        if (e.magnitude < 7.0 || e.magnitude > 12.5) {
          NODELET_WARN("the mean specific force is %.2f m/s^2, not gravity (9.81): check the IMU's units", e.magnitude);
        }
        return;
      }
      why_not = e.message + ", " + std::to_string(received) + " received on " + imu_topic_;
    }
    NODELET_WARN("segment %u: no gravity for the map (%s)", segment_, why_not.c_str());
  }
  // A robot's base on tf is z up by REP-103; the calibration's body (~body_frame, e.g. EuRoC's
  // IMU frame, x up) has no such convention: not taken as level.
  if (!base_frame_.empty() && base_frame_ != body_frame_) {
    Eigen::Isometry3d T_c_base;
    if (cameraToBase(&T_c_base, &why_not, 0.2)) {
      T_map_w_ = mapFromBase(T_c_base.inverse(), T_w_c0);
      map_description_ = "map = " + base_frame_ + " when the first image was taken";
      NODELET_INFO("segment %u: %s", segment_, map_description_.c_str());
      return;
    }
    NODELET_WARN("segment %u: the map cannot follow %s (%s)", segment_, base_frame_.c_str(), why_not.c_str());
  }
  T_map_w_ = mapFromCameraAxes(T_w_c0);
  map_description_ = "map = the first camera in ROS axes (x forward, z up): only as level as that camera";
  NODELET_INFO("segment %u: %s", segment_, map_description_.c_str());
}

bool TrackingNodelet::imuToCamera(Eigen::Matrix3d* R_c_imu, std::string* why) {
  if (have_calibration_file_) {
    // The calibration's T_BS (EuRoC) / T_cam_imu (Kalibr): the camera in the body = IMU frame.
    *R_c_imu = T_b_c_.linear().transpose();
    return true;
  }
  std::string imu_frame;
  {
    std::lock_guard<std::mutex> lock(imu_mutex_);
    imu_frame = imu_frame_;
  }
  if (imu_frame.empty()) {
    *why = "no IMU message yet";
    return false;
  }
  if (!tf_buffer_) {
    *why = "no tf";
    return false;
  }
  try {
    const auto t = tf_buffer_->lookupTransform(frame_id_, imu_frame, ros::Time(0), ros::Duration(0.5));
    *R_c_imu = fromTransformMsg(t.transform).linear();
    return true;
  } catch (const tf2::TransformException& e) {
    *why = "no tf " + imu_frame + " -> " + frame_id_ + " (" + e.what() + ")";
    return false;
  }
}

bool TrackingNodelet::cameraToBase(Eigen::Isometry3d* T_c_base, std::string* why, double timeout_s) {
  if (have_T_c_base_) {
    *T_c_base = T_c_base_;
    return true;
  }
  if (have_calibration_file_ && !body_frame_.empty() && base_frame_ == body_frame_) {
    T_c_base_ = T_b_c_.inverse();  // the mounting from the calibration file, published by this nodelet
    have_T_c_base_ = true;
    *T_c_base = T_c_base_;
    return true;
  }
  if (!tf_buffer_) {
    *why = "no tf";
    return false;
  }
  try {
    // The camera's mounting on the base: static, looked up once.
    const auto t = tf_buffer_->lookupTransform(frame_id_, base_frame_, ros::Time(0), ros::Duration(timeout_s));
    T_c_base_ = fromTransformMsg(t.transform);
    if (!isFinite(T_c_base_)) {
      *why = "non-finite tf";
      return false;
    }
    have_T_c_base_ = true;
    *T_c_base = T_c_base_;
    return true;
  } catch (const tf2::TransformException& e) {
    *why = "no tf " + base_frame_ + " -> " + frame_id_ + " (" + e.what() + ")";
    return false;
  }
}

void TrackingNodelet::publishBodyTransform() {
  // ~body_frame -> camera: the calibration file's T_BS as a static transform.
  if (body_tf_sent_ || body_frame_.empty() || !have_calibration_file_) return;
  const std::string camera = !camera_frame_.empty() ? camera_frame_ : frame_id_;
  if (camera.empty()) return;  // the first image names it
  geometry_msgs::TransformStamped t;
  t.header.stamp = ros::Time::now();
  t.header.frame_id = body_frame_;
  t.child_frame_id = camera;
  t.transform = toTransformMsg(T_b_c_);
  static_broadcaster_->sendTransform(t);
  body_tf_sent_ = true;
  NODELET_INFO("static tf %s -> %s from the calibration's T_BS", body_frame_.c_str(), camera.c_str());
}

}  // namespace vitamin_e_ros
