// TrackingNodelet: the map frame of each map of the session (see vitamin_e/ros/map_frame.h),
// fixed at its first pose, and the check of the camera -> IMU rotation against the gyroscope.
// The core's world is the first reference camera, so T_w_c0 = identity below.
#include <cstdio>

#include <geometry_msgs/TransformStamped.h>

#include "tracking_nodelet.h"
#include "vitamin_e/ros/conversions.h"

namespace vitamin_e_ros {

void TrackingNodelet::alignMap(const vitamin_e::pipeline::FrameResult& result) {
  const Eigen::Isometry3d T_w_c0 = Eigen::Isometry3d::Identity();
  map_alignment_.fixed = true;
  const unsigned map = session().map();
  if (params_.opticalMap()) {
    map_alignment_.T_map_w = Eigen::Isometry3d::Identity();
    map_alignment_.description = "map = the first camera's optical frame";
    return;
  }
  std::string why_not;
  if (!params_.imu_topic.empty()) {
    Eigen::Matrix3d R_c_imu;
    std::string source;
    if (imuToCamera(&R_c_imu, &source, &why_not)) {
      const auto& trajectory = session().system().trajectory();
      const GravityWindow::Estimate e = imu_.upInWorld(
          result.timestamp, params_.gravity_window_s, [&](double t) { return orientationAt(trajectory, t); }, R_c_imu);
      if (e.ok) {
        map_alignment_.T_map_w = mapFromUp(e.up_w, T_w_c0);
        char text[256];
        std::snprintf(text, sizeof(text),
                      "map z up from gravity (%s: %d samples over %.2f s before the initialization, |f| %.2f m/s^2), "
                      "x the first camera's heading",
                      params_.imu_topic.c_str(), e.samples, e.span_s, e.magnitude);
        map_alignment_.description = text;
        NODELET_INFO("map %u: %s", map, text);
        if (e.magnitude < 7.0 || e.magnitude > 12.5) {
          NODELET_WARN("the mean specific force is %.2f m/s^2, not gravity (9.81): check the IMU's units", e.magnitude);
        }
        return;
      }
      why_not = e.message + ", " + std::to_string(imu_.received()) + " received on " + params_.imu_topic;
    }
    NODELET_WARN("map %u: no gravity for the map (%s)", map, why_not.c_str());
  }
  // A robot's base on tf is z up by REP-103; the calibration's body (~body_frame, e.g. EuRoC's
  // IMU frame, x up) has no such convention: not taken as level.
  if (!params_.base_frame.empty() && params_.base_frame != params_.body_frame) {
    Eigen::Isometry3d T_c_base;
    if (cameraToBase(&T_c_base, &why_not, 0.2)) {
      map_alignment_.T_map_w = mapFromBase(T_c_base.inverse(), T_w_c0);
      map_alignment_.description = "map = " + params_.base_frame + " when the first image was taken";
      NODELET_INFO("map %u: %s", map, map_alignment_.description.c_str());
      return;
    }
    NODELET_WARN("map %u: the map cannot follow %s (%s)", map, params_.base_frame.c_str(), why_not.c_str());
  }
  map_alignment_.T_map_w = mapFromCameraAxes(T_w_c0);
  map_alignment_.description = "map = the first camera in ROS axes (x forward, z up): only as level as that camera";
  NODELET_INFO("map %u: %s", map, map_alignment_.description.c_str());
}

bool TrackingNodelet::imuToCamera(Eigen::Matrix3d* R_c_imu, std::string* source, std::string* why) {
  if (!params_.calibration_file.empty()) {
    // The calibration's T_BS (EuRoC) / T_cam_imu (Kalibr): the camera in the body = IMU frame.
    *R_c_imu = T_b_c_.linear().transpose();
    *source = "~calibration_file's T_BS (" + params_.calibration_file + ")";
    return true;
  }
  const std::string imu_frame = imu_.frame();
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
    *source = "tf " + imu_frame + " -> " + frame_id_;
    return true;
  } catch (const tf2::TransformException& e) {
    *why = "no tf " + imu_frame + " -> " + frame_id_ + " (" + e.what() + ")";
    return false;
  }
}

void TrackingNodelet::checkImuRotation(const vitamin_e::pipeline::FrameResult& result) {
  std::string source;  // where the camera -> IMU rotation came from
  const auto gyro_in_camera = [&](double t0, double t1, Eigen::Vector3d* theta_c) {
    Eigen::Vector3d theta_imu;
    Eigen::Matrix3d R_c_imu;
    std::string why;
    if (!imu_.rotationBetween(t0, t1, &theta_imu) || !imuToCamera(&R_c_imu, &source, &why)) return false;
    *theta_c = R_c_imu * theta_imu;
    return true;
  };
  const std::optional<ImuRotationCheck::Verdict> v =
      rotation_check_.add(result.pose_valid, result.timestamp, result.T_w_c.linear(), gyro_in_camera);
  if (!v) return;
  if (!v->agrees) {
    NODELET_WARN("the camera -> IMU rotation from %s looks wrong for this camera: the camera's turns and the "
                 "gyroscope's of %s, rotated into the camera, differ by %.0f deg on average (over %.1f deg of "
                 "rotation, %d frames); the map's z (gravity) is then wrong too. Calibrate T_BS for this "
                 "camera and IMU (a EuRoC calibration on another sensor's bag does not fit)",
                 source.c_str(), params_.imu_topic.c_str(), v->mean_angle_deg, v->rotation_deg, v->intervals);
  } else {
    NODELET_INFO("the camera -> IMU rotation from %s agrees with the gyroscope of %s: %.1f deg apart on average "
                 "(over %.1f deg of rotation, %d frames)",
                 source.c_str(), params_.imu_topic.c_str(), v->mean_angle_deg, v->rotation_deg, v->intervals);
  }
}

bool TrackingNodelet::cameraToBase(Eigen::Isometry3d* T_c_base, std::string* why, double timeout_s) {
  if (have_T_c_base_) {
    *T_c_base = T_c_base_;
    return true;
  }
  if (!params_.calibration_file.empty() && !params_.body_frame.empty() && params_.base_frame == params_.body_frame) {
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
    const auto t = tf_buffer_->lookupTransform(frame_id_, params_.base_frame, ros::Time(0), ros::Duration(timeout_s));
    T_c_base_ = fromTransformMsg(t.transform);
    if (!isFinite(T_c_base_)) {
      *why = "non-finite tf";
      return false;
    }
    have_T_c_base_ = true;
    *T_c_base = T_c_base_;
    return true;
  } catch (const tf2::TransformException& e) {
    *why = "no tf " + params_.base_frame + " -> " + frame_id_ + " (" + e.what() + ")";
    return false;
  }
}

void TrackingNodelet::publishBodyTransform() {
  // ~body_frame -> camera: the calibration file's T_BS as a static transform.
  if (body_tf_sent_ || params_.body_frame.empty() || params_.calibration_file.empty()) return;
  const std::string camera = !params_.camera_frame.empty() ? params_.camera_frame : frame_id_;
  if (camera.empty()) return;  // the first image names it
  geometry_msgs::TransformStamped t;
  t.header.stamp = ros::Time::now();
  t.header.frame_id = params_.body_frame;
  t.child_frame_id = camera;
  t.transform = toTransformMsg(T_b_c_);
  static_broadcaster_->sendTransform(t);
  body_tf_sent_ = true;
  NODELET_INFO("static tf %s -> %s from the calibration's T_BS", params_.body_frame.c_str(), camera.c_str());
}

}  // namespace vitamin_e_ros
