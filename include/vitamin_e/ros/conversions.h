#pragma once
// Conversions between the ROS-free core (Eigen, cv::Mat, camera::Camera) and ROS
// messages, shared by the nodelets. No algorithm here: copies, checks, encodings.
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include <geometry_msgs/Pose.h>
#include <geometry_msgs/Transform.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/PointCloud2.h>
#include <std_msgs/Header.h>

#include "vitamin_e/camera/camera.h"

namespace vitamin_e_ros {

// True when every entry of the pose is finite and the rotation is orthonormal.
bool isFinite(const Eigen::Isometry3d& T);
bool isFinite(const Eigen::Vector3d& p);

geometry_msgs::Pose toPoseMsg(const Eigen::Isometry3d& T);
geometry_msgs::Transform toTransformMsg(const Eigen::Isometry3d& T);
Eigen::Isometry3d fromPoseMsg(const geometry_msgs::Pose& pose);
Eigen::Isometry3d fromTransformMsg(const geometry_msgs::Transform& transform);

// Image message -> CV_8UC1 owning its pixels (mono8 copied; rgb8, bgr8, rgba8,
// bgra8 converted to gray; mono16 / 16UC1 scaled by 1/256: io::toGray8 on a view of
// the message). Returns false and sets *error for any other encoding or a malformed message.
bool toMono8(const sensor_msgs::Image& msg, cv::Mat* gray, std::string* error);

// camera_info -> camera model of the image that comes with it. rectified: an
// image_rect* stream, so P and no distortion; else K and D (plumb_bob,
// rational_polynomial with k4 = k5 = k6 = 0, equidistant, none). Binning and ROI
// (REP-104) scale and shift the intrinsics and give the image size. Throws
// camera::CalibrationError naming what is wrong (bad values, a P without focal
// length, non-zero rational k4..k6, an ROI outside the image).
vitamin_e::camera::Camera cameraFromInfo(const sensor_msgs::CameraInfo& info, bool rectified = false);
// True for a topic whose last name starts with image_rect (image_proc's names).
bool isRectifiedTopic(const std::string& topic);

// sensor_msgs/CompressedImage (jpeg or png, as compressed_image_transport writes
// them) -> CV_8UC1, decoded with OpenCV, then io::toGray8 (colour becomes gray, 16-bit
// is scaled by 1/256). Returns false and sets *error otherwise.
bool compressedToMono8(const sensor_msgs::CompressedImage& msg, cv::Mat* gray, std::string* error);
// "none" | "radial-tangential" | "equidistant".
std::string distortionName(vitamin_e::camera::DistortionModel model);

// A PointCloud2 with fields x, y, z (float32) and intensity (float32).
// intensity may be empty (all zero) or of points' size.
void fillCloud(const std_msgs::Header& header, const std::vector<Eigen::Vector3f>& points,
               const std::vector<std::uint8_t>& intensity, sensor_msgs::PointCloud2* cloud);

// Seconds as text with nanosecond digits ("1403715273.262142976").
std::string stampText(std::uint32_t sec, std::uint32_t nsec);

}  // namespace vitamin_e_ros
