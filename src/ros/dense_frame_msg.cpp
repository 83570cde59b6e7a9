#include "vitamin_e/ros/dense_frame_msg.h"

#include <cmath>

#include "vitamin_e/ros/conversions.h"

namespace vitamin_e_ros {

void toTrackedFrameMsg(const vitamin_e::fusion::DenseFrame& frame, const vitamin_e::camera::Camera& camera,
                       vitamin_e::TrackedFrame* msg) {
  msg->T_w_c = toPoseMsg(frame.T_w_c);
  msg->frame_index = frame.frame_index;
  msg->width = static_cast<uint32_t>(camera.width());
  msg->height = static_cast<uint32_t>(camera.height());
  msg->fx = camera.fx();
  msg->fy = camera.fy();
  msg->cx = camera.cx();
  msg->cy = camera.cy();
  msg->distortion_model = distortionName(camera.model());
  msg->distortion = camera.distortion();
  msg->ids = frame.ids;
  msg->points_c.resize(frame.p_c.size());
  for (std::size_t i = 0; i < frame.p_c.size(); ++i) {
    msg->points_c[i].x = frame.p_c[i].x();
    msg->points_c[i].y = frame.p_c[i].y();
    msg->points_c[i].z = frame.p_c[i].z();
  }
  msg->map_scale = frame.map_scaling.scale;
  msg->map_offset.x = frame.map_scaling.offset.x();
  msg->map_offset.y = frame.map_scaling.offset.y();
  msg->map_offset.z = frame.map_scaling.offset.z();
}

bool fromTrackedFrameMsg(const vitamin_e::TrackedFrame& msg, vitamin_e::fusion::DenseFrame* frame,
                         vitamin_e::meshing::PinholeImage* image, std::string* error) {
  auto fail = [&](const std::string& why) {
    *error = why;
    return false;
  };
  if (msg.ids.size() != msg.points_c.size()) {
    return fail(std::to_string(msg.ids.size()) + " ids but " + std::to_string(msg.points_c.size()) + " points");
  }
  *image = vitamin_e::meshing::PinholeImage{{msg.fx, msg.fy, msg.cx, msg.cy},
                                            static_cast<int>(msg.width),
                                            static_cast<int>(msg.height)};
  try {
    image->validate();
  } catch (const std::exception& e) {
    return fail(std::string("bad intrinsics or image size: ") + e.what());
  }
  frame->T_w_c = fromPoseMsg(msg.T_w_c);
  if (!isFinite(frame->T_w_c)) return fail("a non-finite pose");
  frame->map_scaling.scale = msg.map_scale;
  frame->map_scaling.offset = Eigen::Vector3d(msg.map_offset.x, msg.map_offset.y, msg.map_offset.z);
  if (!frame->map_scaling.isValid()) return fail("a map scale that is not finite and positive");
  frame->frame_index = msg.frame_index;
  frame->ids = msg.ids;
  frame->p_c.resize(msg.points_c.size());
  for (std::size_t i = 0; i < msg.points_c.size(); ++i) {
    const geometry_msgs::Point& p = msg.points_c[i];
    frame->p_c[i] = Eigen::Vector3d(p.x, p.y, p.z);
    if (!frame->p_c[i].allFinite()) return fail("a non-finite point");
  }
  return true;
}

}  // namespace vitamin_e_ros
