#pragma once
// Monocular camera model: pinhole intrinsics plus an optional lens distortion
// (OpenCV/EuRoC radial-tangential or Kannala-Brandt equidistant), and loaders
// for the common calibration file formats (EuRoC sensor.yaml, Kalibr camchain,
// ROS camera_info yaml, KITTI calib.txt).
//
// Coordinates (see docs/DEVELOPING.md): "distorted pixels" are positions in the
// input image; "normalized" coordinates are undistorted (x/z, y/z); "pinhole
// pixels" are K * normalized (camera::Pinhole). Camera frames are optical (z forward).
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "vitamin_e/camera/pinhole.h"

namespace vitamin_e::camera {

enum class DistortionModel {
  kNone,              // pinhole, no coefficients
  kRadialTangential,  // k1 k2 p1 p2 [k3] (OpenCV plumb_bob, EuRoC radial-tangential)
  kEquidistant,       // k1 k2 k3 k4 (Kannala-Brandt; Kalibr equidistant, OpenCV fisheye)
};

const char* toString(DistortionModel model);

struct CalibrationError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

class Camera {
 public:
  Camera() = default;
  // Throws CalibrationError on bad values (size <= 0, f <= 0, wrong coefficient
  // count for the model, non-finite values).
  Camera(int width, int height, double fx, double fy, double cx, double cy,
         DistortionModel model = DistortionModel::kNone, std::vector<double> distortion = {});
  Camera(int width, int height, const Pinhole& K, DistortionModel model = DistortionModel::kNone,
         std::vector<double> distortion = {})
      : Camera(width, height, K.fx, K.fy, K.cx, K.cy, model, std::move(distortion)) {}

  int width() const { return width_; }
  int height() const { return height_; }
  // The pinhole part: K of the undistorted ("pinhole pixel") image.
  const Pinhole& pinhole() const { return pinhole_; }
  double fx() const { return pinhole_.fx; }
  double fy() const { return pinhole_.fy; }
  double cx() const { return pinhole_.cx; }
  double cy() const { return pinhole_.cy; }
  DistortionModel model() const { return model_; }
  const std::vector<double>& distortion() const { return distortion_; }
  bool valid() const { return width_ > 0 && height_ > 0; }

  // Camera-frame point -> distorted pixel; returns false (uv untouched) if
  // p_c.z() <= 1e-9. Optional 2x3 Jacobian of uv w.r.t. p_c.
  bool project(const Eigen::Vector3d& p_c, Eigen::Vector2d* uv,
               Eigen::Matrix<double, 2, 3>* d_uv_d_p_c = nullptr) const;
  // Normalized undistorted (x/z, y/z) -> distorted pixel, optional 2x2 Jacobian.
  Eigen::Vector2d distortNormalized(const Eigen::Vector2d& xy, Eigen::Matrix2d* d_uv_d_xy = nullptr) const;
  // Distorted pixel -> normalized undistorted coordinates (Gauss-Newton on
  // distortNormalized); false if it does not converge to < 1e-8 px.
  bool unprojectNormalized(const Eigen::Vector2d& uv, Eigen::Vector2d* xy) const;
  // Distorted pixel -> unit bearing in the camera frame.
  bool unproject(const Eigen::Vector2d& uv, Eigen::Vector3d* bearing_c) const;
  // Inside [border, width-1-border] x [border, height-1-border].
  bool inImage(const Eigen::Vector2d& uv, double border = 0.0) const;
  // cv::remap maps (CV_32FC1, width x height) producing an undistorted pinhole
  // image with this K and size: map(u,v) = distorted pixel of K^-1 (u,v,1).
  void undistortionMaps(cv::Mat* map_x, cv::Mat* map_y) const;
  // One line: size, intrinsics, model and coefficients.
  std::string describe() const;

 private:
  int width_ = 0;
  int height_ = 0;
  Pinhole pinhole_;
  DistortionModel model_ = DistortionModel::kNone;
  std::vector<double> distortion_;
};

struct CameraCalibration {
  Camera camera;
  // Camera in the body/IMU frame (EuRoC T_BS; Kalibr T_cam_imu inverted).
  Eigen::Isometry3d T_b_c = Eigen::Isometry3d::Identity();
  double rate_hz = 0.0;
  std::string format;  // "euroc", "kalibr", "ros_camera_info", "kitti"
};

// EuRoC ASL sensor.yaml (handles "%YAML:1.0" and "!!opencv-matrix").
CameraCalibration loadEurocSensorYaml(const std::string& path);
// Kalibr camchain yaml (cam0, cam1, ...): intrinsics, distortion_model
// radtan/equidistant/none, resolution, T_cam_imu.
CameraCalibration loadKalibrCamchain(const std::string& path, int cam_index = 0);
// ROS camera_calibration yaml: image_width/height, camera_matrix,
// distortion_model plumb_bob/rational_polynomial(first 5)/equidistant, distortion_coefficients.
CameraCalibration loadRosCameraInfoYaml(const std::string& path);
// KITTI odometry calib.txt: line "P<camera_index>: 12 numbers" (or bare lines);
// KITTI images are rectified, so the model is kNone.
CameraCalibration loadKittiCalib(const std::string& path, int width, int height, int camera_index = 0);
// Detects the format from the content. width/height are needed for KITTI only.
// Throws CalibrationError naming the file and what is wrong.
CameraCalibration loadCalibration(const std::string& path, int width = 0, int height = 0);

}  // namespace vitamin_e::camera
