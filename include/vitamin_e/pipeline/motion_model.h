#pragma once
// Constant-velocity prediction of the next camera pose from the last two. The
// velocity is the last relative motion over the time it took: a frame that
// comes after a gap of dropped frames is predicted that much farther along.
#include <Eigen/Geometry>
#include <cmath>

#include "vitamin_e/common/timing.h"
#include "vitamin_e/geometry/lie.h"

namespace vitamin_e::pipeline {

class MotionModel {
 public:
  bool valid() const { return valid_; }
  // The last pose moved once more by the last relative motion.
  Eigen::Isometry3d predict() const { return T_w_last_ * T_prev_last_; }
  // The pose at time t: the last relative motion scaled (on SE(3)) by the gap
  // since the last pose over the last interval; one step as predict() when the
  // rate is steady or a time is unknown (frameGapRatio, common/timing.h).
  Eigen::Isometry3d predict(double t) const {
    const double r = stepRatio(t);
    if (r == 1.0) return predict();
    return T_w_last_ * geometry::expSE3(r * geometry::logSE3(T_prev_last_));
  }
  const Eigen::Isometry3d& lastPose() const { return T_w_last_; }
  double lastStepLength() const { return T_prev_last_.translation().norm(); }  // map units
  // A new pose: the motion from the previous one becomes the velocity. t: its
  // time in seconds (NaN: unknown; then steps are counted in frames).
  void update(const Eigen::Isometry3d& T_w_c, double t = std::nan("")) {
    T_prev_last_ = T_w_last_.inverse() * T_w_c;
    T_w_last_ = T_w_c;
    interval_ = std::isfinite(t) && std::isfinite(t_last_) && t > t_last_ ? t - t_last_ : std::nan("");
    t_last_ = t;
    valid_ = true;
  }
  // The last pose refined (by a keyframe BA): the velocity is kept.
  void correctLast(const Eigen::Isometry3d& T_w_c) { T_w_last_ = T_w_c; }
  // interval: the time T_prev_last took [s] (NaN: unknown), t: the time of T_w_c.
  void restart(const Eigen::Isometry3d& T_w_c, const Eigen::Isometry3d& T_prev_last, double t = std::nan(""),
               double interval = std::nan("")) {
    T_w_last_ = T_w_c;
    T_prev_last_ = T_prev_last;
    t_last_ = t;
    interval_ = interval;
    valid_ = true;
  }
  void invalidate() { valid_ = false; }
  // The map was rescaled about the last pose's centre: the velocity's step follows.
  void rescale(double factor) { T_prev_last_.translation() *= factor; }
  // The gap to time t over the last interval: frameGapRatio (1 when steady or unknown).
  double stepRatio(double t) const { return frameGapRatio(t - t_last_, interval_); }

 private:
  bool valid_ = false;
  Eigen::Isometry3d T_w_last_ = Eigen::Isometry3d::Identity();
  // The last frame in the frame before it (p_prev = T_prev_last * p_last).
  Eigen::Isometry3d T_prev_last_ = Eigen::Isometry3d::Identity();
  double t_last_ = std::nan("");    // time of T_w_last_ [s]
  double interval_ = std::nan("");  // time T_prev_last_ took [s]
};

}  // namespace vitamin_e::pipeline
