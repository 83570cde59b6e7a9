#pragma once
// The IMU messages the tracking nodelet keeps: the IMU callback adds, the SLAM thread
// reads (thread-safe). The accelerometer gives the map's gravity (GravityWindow); the
// gyroscope checks the camera -> IMU rotation against the camera's own rotation
// (RotationAgreement, ImuRotationCheck). Plain Eigen: unit-tested without a master.
#include <cstddef>
#include <deque>
#include <functional>
#include <mutex>
#include <optional>
#include <string>

#include <Eigen/Geometry>

#include "vitamin_e/ros/map_frame.h"

namespace vitamin_e_ros {

class ImuBuffer {
 public:
  // In time order; a sample older than the newest by more than 1 s (the clock went back,
  // a bag played again) starts the buffer over. Bounded: at most max_samples are kept.
  void add(double t, const Eigen::Vector3d& specific_force, const Eigen::Vector3d& angular_rate,
           const std::string& frame_id);
  void dropBefore(double t);
  std::string frame() const;  // of the first message ("" before one)
  std::size_t received() const;
  GravityWindow::Estimate upInWorld(double t_end, double window_s,
                                    const std::function<Eigen::Matrix3d(double)>& R_w_c_at,
                                    const Eigen::Matrix3d& R_c_imu) const;
  // The gyroscope's rotation vector over (t0, t1] (rad, IMU frame; the rates integrated,
  // a small rotation). False when the samples do not cover the interval.
  bool rotationBetween(double t0, double t1, Eigen::Vector3d* theta_imu) const;

  static constexpr std::size_t kMaxSamples = 100000;  // about 8 min at 200 Hz

 private:
  struct Rate {
    double t;
    Eigen::Vector3d w;
  };
  mutable std::mutex mutex_;
  GravityWindow gravity_;
  std::deque<Rate> rates_;
  std::string frame_;
  std::size_t received_ = 0;
};

// Does the camera turn as the gyroscope says, once rotated into the camera by R_c_imu?
// Each interval between two camera poses gives the camera's rotation increment theta_c
// (its own frame: R_k = R_{k-1} exp(theta_c)) and the gyroscope's over the same time,
// R_c_imu theta_imu. The agreement is the mean angle between them, weighted by their
// lengths: a few degrees with the right R_c_imu (noise, bias), tens of degrees with another
// camera's. The scale of the map plays no part.
class RotationAgreement {
 public:
  void add(const Eigen::Vector3d& theta_c, const Eigen::Vector3d& theta_imu_in_c);
  int intervals() const { return intervals_; }
  double cameraRotationDeg() const;  // sum of |theta_c|
  double meanAngleDeg() const;       // 0 while nothing was added

 private:
  int intervals_ = 0;
  double sum_c_ = 0.0, sum_dot_ = 0.0, sum_norms_ = 0.0;
};

// The camera -> IMU rotation checked once over the tracked poses: every interval between two
// consecutive frames with a pose adds the camera's rotation and the gyroscope's to a
// RotationAgreement, until the camera has turned enough to tell a wrong mounting (tens of
// degrees off) from gyroscope noise and bias; then the verdict, once.
class ImuRotationCheck {
 public:
  static constexpr double kMinRotationDeg = 8.0;
  static constexpr int kMinIntervals = 10;
  static constexpr double kMaxMeanAngleDeg = 30.0;  // a mean angle above: the rotation is wrong

  struct Verdict {
    bool agrees = false;          // mean_angle_deg <= kMaxMeanAngleDeg
    double mean_angle_deg = 0.0;  // RotationAgreement::meanAngleDeg
    double rotation_deg = 0.0;    // the camera's rotation it was judged over
    int intervals = 0;
  };
  // The gyroscope's rotation vector over (t0, t1], in the camera frame; false when it is not
  // available (samples missing, no camera -> IMU rotation).
  using GyroInCamera = std::function<bool(double t0, double t1, Eigen::Vector3d* theta_c)>;

  // A frame: its camera orientation when it has a pose (pose_valid false: the next pose starts a
  // new interval). Returns the verdict at the frame that decides it, and nothing before or after.
  std::optional<Verdict> add(bool pose_valid, double t, const Eigen::Matrix3d& R_w_c, const GyroInCamera& gyro);
  void restart() { have_pose_ = false; }  // a new map or path: no interval across it
  bool decided() const { return decided_; }

 private:
  bool have_pose_ = false;
  double t_ = 0.0;
  Eigen::Matrix3d R_w_c_ = Eigen::Matrix3d::Identity();
  RotationAgreement agreement_;
  bool decided_ = false;
};

}  // namespace vitamin_e_ros
