// TrackingNodelet: FrameResult (already in the map frame) -> messages, where the results come
// (see Threads in tracking_nodelet.h; the publishing options are options_, the frame's copy of the reconfigure values). Every
// pose and point is checked finite before it is published (a non-finite one is skipped with a
// throttled error).
#include <cmath>

#include <cv_bridge/cv_bridge.h>
#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/TransformStamped.h>
#include <nav_msgs/Odometry.h>
#include <sensor_msgs/PointCloud2.h>
#include <sensor_msgs/image_encodings.h>
#include <opencv2/imgproc.hpp>

#include "tracking_nodelet.h"
#include "vitamin_e/TrackedFrame.h"
#include "vitamin_e/TrackingStatus.h"
#include "vitamin_e/pipeline/step_covariance.h"
#include "vitamin_e/ros/conversions.h"
#include "vitamin_e/ros/dense_frame_msg.h"

namespace vitamin_e_ros {

using vitamin_e::pipeline::FramePose;
using vitamin_e::pipeline::FrameResult;
using vitamin_e::pipeline::TrackingState;

void TrackingNodelet::publishResult(const FrameResult& result, const QueuedFrame& frame, double ms,
                                    bool pose_published) {
  const std_msgs::Header& header = frame.header;
  vitamin_e::TrackingStatusPtr status(new vitamin_e::TrackingStatus);
  status->header = header;
  status->header.frame_id = frame_id_;
  status->state = result.state == TrackingState::kTracking       ? vitamin_e::TrackingStatus::TRACKING
                  : result.state == TrackingState::kLost         ? vitamin_e::TrackingStatus::LOST
                  : result.state == TrackingState::kRelocalizing ? vitamin_e::TrackingStatus::RELOCALIZING
                                                                 : vitamin_e::TrackingStatus::INITIALIZING;
  status->state_name = vitamin_e::pipeline::toString(result.state);
  status->frame_index = result.frame_index;
  status->num_tracked = static_cast<uint32_t>(result.num_tracked);
  status->num_mapped = static_cast<uint32_t>(result.num_mapped);
  status->map_size = static_cast<uint32_t>(result.map_size);
  status->init_retries = session().initRetries();
  status->relocalizations = session().relocalizations();
  status->ms_per_frame = static_cast<float>(ms);
  status->frames_processed = session().framesProcessed();
  status->frames_tracked = session().framesTracked();
  status->segment = session().segment();
  status->map = session().map();
  status->message = result.message;
  if (session().system().mapLoaded()) {  // a map from ~load_map: say whether the camera is in it
    const std::string where = result.pose_valid ? "localizing in loaded map" : "lost in loaded map";
    status->message = result.message.empty() ? where : where + ": " + result.message;
  }
  status_pub_.publish(status);
  {
    std::lock_guard<std::mutex> lock(stats_mutex_);
    stats_.processed_wall.push_back(ros::WallTime::now().toSec());
    ++stats_.processed;
    stats_.state = status->state;
    stats_.state_name = status->state_name;
    stats_.message = result.message;
    stats_.tracked = result.num_tracked;
    stats_.mapped = result.num_mapped;
    stats_.map_size = result.map_size;
    stats_.init_retries = session().initRetries();
    while (stats_.processed_wall.size() > 2000) stats_.processed_wall.pop_front();
  }

  // Every result goes through the mesher's input, which adds up the map's scale corrections; the
  // points only when the mesher listens.
  if (dense_input_map_ != session().map()) {
    dense_input_.reset();  // a new map
    dense_input_map_ = session().map();
  }
  const bool to_mesher = frame_pub_.getNumSubscribers() > 0;
  const vitamin_e::fusion::DenseFrame dense = dense_input_.next(result, to_mesher && result.pose_valid);
  if (result.pose_valid) {
    if (isFinite(result.T_w_c)) {
      if (!pose_published) publishFramePose(vitamin_e::pipeline::poseOf(result), header);
      if (options_.publish_points && points_pub_.getNumSubscribers() > 0) publishPoints(result, header);
      if (to_mesher) publishFrame(dense, header);
    } else {
      NODELET_ERROR_THROTTLE(2.0, "frame %lu: non-finite pose not published",
                             static_cast<unsigned long>(result.frame_index));
    }
  }
  if (options_.map_points_period > 0.0 && map_points_pub_.getNumSubscribers() > 0 &&
      (last_map_points_.isZero() || (header.stamp - last_map_points_).toSec() >= options_.map_points_period ||
       header.stamp < last_map_points_)) {
    publishMapPoints(header.stamp);
    last_map_points_ = header.stamp;
  }
  if (tracking_image_pub_.getNumSubscribers() > 0) publishTrackingImage(result, header, frame.gray);
}

void TrackingNodelet::publishFramePose(const FramePose& pose, const std_msgs::Header& header) {
  if (!isFinite(pose.T_w_c)) {
    NODELET_ERROR_THROTTLE(2.0, "frame %lu: non-finite pose not published",
                           static_cast<unsigned long>(pose.frame_index));
    return;
  }
  publishPose(pose, header);
  if (options_.publish_tf) publishTf(pose.T_w_c, header.stamp);
  std::lock_guard<std::mutex> lock(stats_mutex_);
  stats_.latency_s.push_back((ros::Time::now() - header.stamp).toSec());
  while (stats_.latency_s.size() > 200) stats_.latency_s.pop_front();
}

void TrackingNodelet::publishPose(const FramePose& frame_pose, const std_msgs::Header& header) {
  const Eigen::Isometry3d& T_map_c = frame_pose.T_w_c;
  const geometry_msgs::Pose pose = toPoseMsg(T_map_c);
  geometry_msgs::PoseStampedPtr stamped(new geometry_msgs::PoseStamped);
  stamped->header.stamp = header.stamp;
  stamped->header.frame_id = params_.map_frame;
  stamped->pose = pose;
  pose_pub_.publish(stamped);

  // Odometry of ~base_frame when set (the camera's mounting from tf or the calibration), else
  // of the camera. Covariance: of the step from the previous frame (pipeline::stepCovariance),
  // in ROS's convention (map-frame position, rotation about the map axes); without one (the
  // initialization frame, a relocalized one) a large diagonal, not the zeros an EKF would read
  // as certainty.
  Eigen::Isometry3d T_map_child = T_map_c;
  std::string child = frame_id_;
  Eigen::Vector3d lever = Eigen::Vector3d::Zero();
  if (!params_.base_frame.empty()) {
    Eigen::Isometry3d T_c_base;
    std::string why;
    if (!cameraToBase(&T_c_base, &why)) {
      NODELET_WARN_THROTTLE(5.0, "~odometry not published: %s", why.c_str());
      publishPath(stamped);
      return;
    }
    T_map_child = T_map_c * T_c_base;
    child = params_.base_frame;
    lever = T_map_c.linear() * T_c_base.translation();
  }
  nav_msgs::OdometryPtr odom(new nav_msgs::Odometry);
  odom->header = stamped->header;
  odom->child_frame_id = child;
  odom->pose.pose = toPoseMsg(T_map_child);
  Matrix6d cov = Matrix6d::Identity() * 1e3;
  Matrix6d step;
  if (previous_pose_valid_ && vitamin_e::pipeline::stepCovariance(frame_pose, &step)) {
    cov = covarianceMovedTo(covarianceInParent(step, T_map_c.linear()), lever);
  }
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 6; ++c) odom->pose.covariance[6 * r + c] = cov(r, c);
  odom->twist.covariance[0] = -1.0;  // twist not estimated
  odom_pub_.publish(odom);
  publishPath(stamped);
}

void TrackingNodelet::publishPath(const geometry_msgs::PoseStampedConstPtr& stamped) {
  path_.header.stamp = stamped->header.stamp;
  path_.poses.push_back(*stamped);
  if (options_.path_max_poses > 0 && path_.poses.size() > static_cast<std::size_t>(options_.path_max_poses)) {
    path_.poses.erase(path_.poses.begin(), path_.poses.end() - options_.path_max_poses);
  }
  if (path_pub_.getNumSubscribers() > 0) path_pub_.publish(path_);
}

void TrackingNodelet::publishTf(const Eigen::Isometry3d& T_map_c, const ros::Time& stamp) {
  geometry_msgs::TransformStamped tf;
  tf.header.stamp = stamp;
  tf.header.frame_id = params_.map_frame;
  const std::string& odom_frame = params_.odom_frame;
  const std::string& base_frame = params_.base_frame;
  if (!odom_frame.empty() && !base_frame.empty() && tf_buffer_) {
    // REP-105: map -> odom = T_map_cam * T_cam_odom, with cam -> base -> odom from tf.
    geometry_msgs::TransformStamped cam_odom;
    try {
      cam_odom = tf_buffer_->lookupTransform(frame_id_, odom_frame, stamp, ros::Duration(0.05));
    } catch (const tf2::TransformException& e) {
      NODELET_WARN_THROTTLE(5.0, "no %s -> %s at %.3f (%s): map -> %s not published", odom_frame.c_str(),
                            frame_id_.c_str(), stamp.toSec(), e.what(), odom_frame.c_str());
      return;
    }
    const Eigen::Isometry3d T_map_odom = T_map_c * fromTransformMsg(cam_odom.transform);
    if (!isFinite(T_map_odom)) {
      NODELET_ERROR_THROTTLE(2.0, "non-finite map -> odom not published");
      return;
    }
    tf.child_frame_id = odom_frame;
    tf.transform = toTransformMsg(T_map_odom);
  } else if (!base_frame.empty()) {
    // The camera hangs under the base (its mounting is static): map -> base, so that the
    // camera frame keeps one parent.
    Eigen::Isometry3d T_c_base;
    std::string why;
    if (!cameraToBase(&T_c_base, &why)) {
      NODELET_WARN_THROTTLE(5.0, "map -> %s not published: %s", base_frame.c_str(), why.c_str());
      return;
    }
    tf.child_frame_id = base_frame;
    tf.transform = toTransformMsg(T_map_c * T_c_base);
  } else {
    tf.child_frame_id = frame_id_;
    tf.transform = toTransformMsg(T_map_c);
  }
  tf_broadcaster_->sendTransform(tf);
}

void TrackingNodelet::publishPoints(const FrameResult& result, const std_msgs::Header& header) {
  std::vector<Eigen::Vector3f> points;
  std::vector<std::uint8_t> intensity;
  points.reserve(result.points.size());
  intensity.reserve(result.points.size());
  const Eigen::Isometry3d T_c_w = result.T_w_c.inverse();
  std::size_t skipped = 0;
  for (const auto& p : result.points) {
    if (!p.has_position) continue;
    if (!isFinite(p.p_w)) {
      ++skipped;
      continue;
    }
    if (options_.points_max_depth > 0.0 && (T_c_w * p.p_w).z() > options_.points_max_depth) continue;
    points.push_back(p.p_w.cast<float>());
    intensity.push_back(p.intensity);
  }
  if (skipped > 0) NODELET_ERROR_THROTTLE(2.0, "%zu non-finite points not published", skipped);
  sensor_msgs::PointCloud2Ptr cloud(new sensor_msgs::PointCloud2);
  std_msgs::Header h = header;
  h.frame_id = params_.map_frame;
  fillCloud(h, points, intensity, cloud.get());
  points_pub_.publish(cloud);
}

void TrackingNodelet::publishFrame(const vitamin_e::fusion::DenseFrame& dense, const std_msgs::Header& header) {
  vitamin_e::TrackedFramePtr frame(new vitamin_e::TrackedFrame);
  toTrackedFrameMsg(dense, session().system().camera(), frame.get());
  frame->header.stamp = header.stamp;
  frame->header.frame_id = params_.map_frame;
  // The map's number: the mesher starts a new TSDF with a new map, not at a time jump in the same one.
  frame->segment = session().map();
  frame_pub_.publish(vitamin_e::TrackedFrameConstPtr(frame));  // zero copy inside one manager
}

void TrackingNodelet::publishMapPoints(const ros::Time& stamp) {
  const auto map = session().system().mapPoints();
  std::vector<Eigen::Vector3f> points;
  std::vector<std::uint8_t> intensity;
  points.reserve(map.size());
  intensity.reserve(map.size());
  for (const auto& p : map) {
    if (!isFinite(p.p_w)) continue;
    points.push_back((map_alignment_.T_map_w * p.p_w).cast<float>());
    intensity.push_back(p.intensity);
  }
  if (points.size() < map.size()) {
    NODELET_ERROR_THROTTLE(2.0, "%zu non-finite map points not published", map.size() - points.size());
  }
  sensor_msgs::PointCloud2Ptr cloud(new sensor_msgs::PointCloud2);
  std_msgs::Header h;
  h.stamp = stamp;
  h.frame_id = params_.map_frame;
  fillCloud(h, points, intensity, cloud.get());
  map_points_pub_.publish(cloud);
}

void TrackingNodelet::publishTrackingImage(const FrameResult& result, const std_msgs::Header& header,
                                           const cv::Mat& gray) {
  cv_bridge::CvImage out;
  out.header = header;
  out.encoding = sensor_msgs::image_encodings::BGR8;
  cv::cvtColor(gray, out.image, cv::COLOR_GRAY2BGR);
  const std::size_t history = static_cast<std::size_t>(std::max(0, options_.draw_track_length));
  std::map<std::uint64_t, std::deque<cv::Point2f>> alive;
  for (const auto& p : result.points) {
    if (!p.uv.allFinite()) continue;
    const cv::Point2f uv(p.uv.x(), p.uv.y());
    auto& trail = alive[p.track_id];
    auto old = track_history_.find(p.track_id);
    if (old != track_history_.end()) trail = std::move(old->second);
    trail.push_back(uv);
    while (trail.size() > history + 1) trail.pop_front();
    const cv::Scalar color = p.has_position ? cv::Scalar(0, 220, 0) : cv::Scalar(0, 160, 255);
    for (std::size_t k = 1; k < trail.size(); ++k) cv::line(out.image, trail[k - 1], trail[k], color, 1, cv::LINE_AA);
    cv::circle(out.image, uv, 2, color, -1, cv::LINE_AA);
  }
  track_history_ = std::move(alive);
  const std::string text = std::string(vitamin_e::pipeline::toString(result.state)) + "  tracks " +
                           std::to_string(result.num_tracked) + "  mapped " + std::to_string(result.num_mapped);
  cv::putText(out.image, text, cv::Point(8, 20), cv::FONT_HERSHEY_SIMPLEX, 0.55, cv::Scalar(0, 0, 255), 1, cv::LINE_AA);
  tracking_image_pub_.publish(out.toImageMsg());
}

}  // namespace vitamin_e_ros
