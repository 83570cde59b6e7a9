#pragma once
// Constant-velocity prediction of the next camera pose from the last two.
#include <Eigen/Geometry>

namespace vitamin_e::pipeline {

class MotionModel {
 public:
  bool valid() const { return valid_; }
  // The last pose moved once more by the last relative motion.
  Eigen::Isometry3d predict() const { return T_w_last_ * T_prev_last_; }
  const Eigen::Isometry3d& lastPose() const { return T_w_last_; }
  double lastStepLength() const { return T_prev_last_.translation().norm(); }  // map units
  // A new pose: the motion from the previous one becomes the velocity.
  void update(const Eigen::Isometry3d& T_w_c) {
    T_prev_last_ = T_w_last_.inverse() * T_w_c;
    T_w_last_ = T_w_c;
    valid_ = true;
  }
  // The last pose refined (by a keyframe BA): the velocity is kept.
  void correctLast(const Eigen::Isometry3d& T_w_c) { T_w_last_ = T_w_c; }
  void restart(const Eigen::Isometry3d& T_w_c, const Eigen::Isometry3d& T_prev_last) {
    T_w_last_ = T_w_c;
    T_prev_last_ = T_prev_last;
    valid_ = true;
  }
  void invalidate() { valid_ = false; }
  // The map was rescaled about the last pose's centre: the velocity's step follows.
  void rescale(double factor) { T_prev_last_.translation() *= factor; }

 private:
  bool valid_ = false;
  Eigen::Isometry3d T_w_last_ = Eigen::Isometry3d::Identity();
  // The last frame in the frame before it (p_prev = T_prev_last * p_last).
  Eigen::Isometry3d T_prev_last_ = Eigen::Isometry3d::Identity();
};

}  // namespace vitamin_e::pipeline
