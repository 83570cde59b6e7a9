#include "vitamin_e/ros/conversions.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <sensor_msgs/image_encodings.h>
#include <sensor_msgs/point_cloud2_iterator.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "vitamin_e/io/dataset.h"

namespace vitamin_e_ros {

namespace enc = sensor_msgs::image_encodings;
using vitamin_e::camera::CalibrationError;
using vitamin_e::camera::Camera;
using vitamin_e::camera::DistortionModel;
using vitamin_e::camera::Pinhole;
using vitamin_e::io::ChannelOrder;

bool isFinite(const Eigen::Isometry3d& T) {
  if (!T.matrix().allFinite()) return false;
  const Eigen::Matrix3d R = T.linear();
  return (R.transpose() * R - Eigen::Matrix3d::Identity()).norm() < 1e-6;
}

bool isFinite(const Eigen::Vector3d& p) { return p.allFinite(); }

geometry_msgs::Pose toPoseMsg(const Eigen::Isometry3d& T) {
  geometry_msgs::Pose pose;
  const Eigen::Quaterniond q(T.linear());
  pose.position.x = T.translation().x();
  pose.position.y = T.translation().y();
  pose.position.z = T.translation().z();
  pose.orientation.w = q.w();
  pose.orientation.x = q.x();
  pose.orientation.y = q.y();
  pose.orientation.z = q.z();
  return pose;
}

geometry_msgs::Transform toTransformMsg(const Eigen::Isometry3d& T) {
  const geometry_msgs::Pose pose = toPoseMsg(T);
  geometry_msgs::Transform tf;
  tf.translation.x = pose.position.x;
  tf.translation.y = pose.position.y;
  tf.translation.z = pose.position.z;
  tf.rotation = pose.orientation;
  return tf;
}

Eigen::Isometry3d fromPoseMsg(const geometry_msgs::Pose& pose) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  const Eigen::Quaterniond q(pose.orientation.w, pose.orientation.x, pose.orientation.y, pose.orientation.z);
  T.linear() = q.normalized().toRotationMatrix();
  T.translation() = Eigen::Vector3d(pose.position.x, pose.position.y, pose.position.z);
  return T;
}

Eigen::Isometry3d fromTransformMsg(const geometry_msgs::Transform& transform) {
  geometry_msgs::Pose pose;
  pose.position.x = transform.translation.x;
  pose.position.y = transform.translation.y;
  pose.position.z = transform.translation.z;
  pose.orientation = transform.rotation;
  return fromPoseMsg(pose);
}

bool toMono8(const sensor_msgs::Image& msg, cv::Mat* gray, std::string* error) {
  const std::string& e = msg.encoding;
  int cv_type = -1;
  int channels = 1;
  if (e == enc::MONO8 || e == enc::TYPE_8UC1) {
    cv_type = CV_8UC1;
  } else if (e == enc::MONO16 || e == enc::TYPE_16UC1) {
    cv_type = CV_16UC1;
  } else if (e == enc::RGB8 || e == enc::BGR8) {
    cv_type = CV_8UC3;
    channels = 3;
  } else if (e == enc::RGBA8 || e == enc::BGRA8) {
    cv_type = CV_8UC4;
    channels = 4;
  } else {
    *error = "unsupported image encoding '" + e + "' (mono8, mono16, rgb8, bgr8, rgba8, bgra8)";
    return false;
  }
  const std::size_t bytes_per_pixel = static_cast<std::size_t>(channels) * (cv_type == CV_16UC1 ? 2 : 1);
  if (msg.width == 0 || msg.height == 0 || msg.step < msg.width * bytes_per_pixel ||
      msg.data.size() < static_cast<std::size_t>(msg.step) * msg.height) {
    *error = "malformed image message (" + std::to_string(msg.width) + "x" + std::to_string(msg.height) + ", step " +
             std::to_string(msg.step) + ", " + std::to_string(msg.data.size()) + " bytes)";
    return false;
  }
  const bool big_endian_host = false;
  if (cv_type == CV_16UC1 && static_cast<bool>(msg.is_bigendian) != big_endian_host) {
    *error = "big-endian 16-bit images are not supported";
    return false;
  }
  // A view on the message's buffer; the result always owns its pixels (the core may
  // keep the image beyond the message's lifetime).
  const cv::Mat view(static_cast<int>(msg.height), static_cast<int>(msg.width), cv_type,
                     const_cast<std::uint8_t*>(msg.data.data()), msg.step);
  const bool rgb = e == enc::RGB8 || e == enc::RGBA8;
  *gray = vitamin_e::io::toGray8(view, rgb ? ChannelOrder::kRgb : ChannelOrder::kBgr);
  if (gray->data == view.data) *gray = gray->clone();  // mono8: toGray8 shares the pixels
  return true;
}

Camera cameraFromInfo(const sensor_msgs::CameraInfo& info, bool rectified) {
  // Full-resolution intrinsics: P (rectified image, no distortion) or K and D (raw image).
  Pinhole K;
  if (rectified) {
    K = {info.P[0], info.P[5], info.P[2], info.P[6]};
    if (!(K.fx > 0.0) || !(K.fy > 0.0)) {
      throw CalibrationError("camera_info: rectified image but P has no focal length (P = 0: an uncalibrated camera?)");
    }
  } else {
    K = {info.K[0], info.K[4], info.K[2], info.K[5]};
  }
  // REP-104: the ROI is a window of the full-resolution image; binning then divides it.
  const double bx = info.binning_x > 1 ? info.binning_x : 1.0;
  const double by = info.binning_y > 1 ? info.binning_y : 1.0;
  const bool roi = info.roi.width > 0 && info.roi.height > 0;
  if (roi && (info.roi.x_offset + info.roi.width > info.width || info.roi.y_offset + info.roi.height > info.height)) {
    throw CalibrationError("camera_info: roi " + std::to_string(info.roi.width) + "x" +
                           std::to_string(info.roi.height) + "+" + std::to_string(info.roi.x_offset) + "+" +
                           std::to_string(info.roi.y_offset) + " lies outside the " + std::to_string(info.width) + "x" +
                           std::to_string(info.height) + " image");
  }
  const double full_w = roi ? info.roi.width : info.width;
  const double full_h = roi ? info.roi.height : info.height;
  const int width = static_cast<int>(full_w / bx);
  const int height = static_cast<int>(full_h / by);
  if (roi) {
    K.cx -= info.roi.x_offset;
    K.cy -= info.roi.y_offset;
  }
  // Pinhole::binned keeps the binned pixel's centre (image_geometry's cx / bx drops that
  // half-pixel shift).
  K = K.binned(bx, by);
  // A driver without a calibration publishes a placeholder (image_publisher: fx = fy = 1). No
  // real lens has a focal length below 1/20 of the image (a pinhole's field of view > 169 deg; a
  // 220 deg fisheye has f ~ w / 4).
  if (K.fx > 0.0 && K.fy > 0.0 && (K.fx < width / 20.0 || K.fy < height / 20.0)) {
    throw CalibrationError("camera_info: focal length fx=" + std::to_string(K.fx) + " fy=" + std::to_string(K.fy) +
                           " px for a " + std::to_string(width) + "x" + std::to_string(height) +
                           " image is a placeholder, not a calibration (an uncalibrated driver?): calibrate the "
                           "camera (camera_calibration) and give the driver its camera_info_url, or set "
                           "~calibration_file");
  }

  const std::string& m = info.distortion_model;
  std::vector<double> d(info.D.begin(), info.D.end());
  const bool all_zero = std::all_of(d.begin(), d.end(), [](double v) { return v == 0.0; });
  if (rectified || d.empty() || all_zero) return Camera(width, height, K);
  if (m == "plumb_bob" || m == "rational_polynomial") {
    // The core's radial-tangential model has k1 k2 p1 p2 k3: refuse what it would silently drop.
    for (std::size_t k = 5; k < d.size(); ++k) {
      if (d[k] != 0.0) {
        throw CalibrationError("camera_info: " + m + " coefficient D[" + std::to_string(k) +
                               "] = " + std::to_string(d[k]) +
                               " is not supported (only k1 k2 p1 p2 k3; the rational k4..k6 must be 0): "
                               "publish the rectified image (image_rect) or calibrate with plumb_bob");
      }
    }
    if (d.size() > 5) d.resize(5);
    if (d.size() == 5 && d[4] == 0.0) d.resize(4);
    return Camera(width, height, K, DistortionModel::kRadialTangential, d);
  }
  if (m == "equidistant" || m == "fisheye") {
    return Camera(width, height, K, DistortionModel::kEquidistant, d);
  }
  throw CalibrationError("camera_info: unsupported distortion_model '" + m + "'");
}

bool isRectifiedTopic(const std::string& topic) {
  const std::size_t slash = topic.find_last_of('/');
  const std::string last = slash == std::string::npos ? topic : topic.substr(slash + 1);
  return last.rfind("image_rect", 0) == 0;
}

bool compressedToMono8(const sensor_msgs::CompressedImage& msg, cv::Mat* gray, std::string* error) {
  if (msg.format.find("compressedDepth") != std::string::npos) {
    *error = "compressedDepth images are not camera images (format '" + msg.format + "')";
    return false;
  }
  if (msg.data.empty()) {
    *error = "empty compressed image (format '" + msg.format + "')";
    return false;
  }
  cv::Mat decoded;
  try {
    decoded =
        cv::imdecode(cv::Mat(1, static_cast<int>(msg.data.size()), CV_8UC1, const_cast<std::uint8_t*>(msg.data.data())),
                     cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception& e) {
    decoded.release();
  }
  if (decoded.empty()) {
    *error = "cannot decode the compressed image (format '" + msg.format + "', " + std::to_string(msg.data.size()) +
             " bytes)";
    return false;
  }
  // OpenCV decodes colour as BGR(A) whatever the original encoding was.
  try {
    *gray = vitamin_e::io::toGray8(decoded, ChannelOrder::kBgr);
  } catch (const vitamin_e::io::DatasetError& e) {
    *error = std::string("decoded image: ") + e.what() + " (format '" + msg.format + "')";
    return false;
  }
  return true;
}

std::string distortionName(DistortionModel model) {
  switch (model) {
    case DistortionModel::kRadialTangential: return "radial-tangential";
    case DistortionModel::kEquidistant: return "equidistant";
    default: return "none";
  }
}

void fillCloud(const std_msgs::Header& header, const std::vector<Eigen::Vector3f>& points,
               const std::vector<std::uint8_t>& intensity, sensor_msgs::PointCloud2* cloud) {
  cloud->header = header;
  cloud->height = 1;
  cloud->is_dense = true;
  cloud->is_bigendian = false;
  sensor_msgs::PointCloud2Modifier modifier(*cloud);
  modifier.setPointCloud2Fields(4, "x", 1, sensor_msgs::PointField::FLOAT32, "y", 1, sensor_msgs::PointField::FLOAT32,
                                "z", 1, sensor_msgs::PointField::FLOAT32, "intensity", 1,
                                sensor_msgs::PointField::FLOAT32);
  modifier.resize(points.size());
  // The field iterators take data.front(): undefined behaviour on an empty cloud.
  if (points.empty()) return;
  sensor_msgs::PointCloud2Iterator<float> x(*cloud, "x"), y(*cloud, "y"), z(*cloud, "z"), i(*cloud, "intensity");
  const bool has_intensity = intensity.size() == points.size();
  for (std::size_t k = 0; k < points.size(); ++k, ++x, ++y, ++z, ++i) {
    *x = points[k].x();
    *y = points[k].y();
    *z = points[k].z();
    *i = has_intensity ? static_cast<float>(intensity[k]) : 0.0f;
  }
}

std::string stampText(std::uint32_t sec, std::uint32_t nsec) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%u.%09u", sec, nsec);
  return buf;
}

}  // namespace vitamin_e_ros
