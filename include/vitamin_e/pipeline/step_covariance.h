#pragma once
// The covariance of the frame-to-frame motion, what an odometry filter (an EKF such as
// robot_localization) fuses: the error of the step from the previous tracked frame to this
// one, as the right perturbation delta = (rho, phi) of T_w_c in the camera frame
// (T_prev^-1 T_w_c = true step * expSE3(delta)), map units^2 and rad^2. Monocular: the map's
// scale is not observed, so nothing here covers a scale error or drift.
//
// It is made from the per-frame BA's covariance of the frame's own measurements
// (FrameResult::T_w_c_covariance with ba.covariance given_points: the map held as it is;
// the map's own error is common to consecutive frames and cancels in their step), scaled by
// a model fitted to the true step errors of a render with exact ground truth:
//   - scale: the tracker's point errors are partly common to consecutive frames (a track's
//     error persists), so the step's error is somewhat below one frame's own noise;
//   - keyframe_scale: at a keyframe the window BA moves the frame and the map as well.
// bench_system_step_covariance measures the NEES of the steps on any render (6 is right).
#include <Eigen/Core>

#include "vitamin_e/pipeline/frame_result.h"

namespace vitamin_e::pipeline {

struct StepCovarianceModel {
  // Fitted so that the mean NEES of the steps is 6 on the EuRoC V1_01 render
  // (render_sequence.py, motion blur): non-keyframe and keyframe steps alike.
  double scale = 0.8;
  double keyframe_scale = 2.5;
};

// The step covariance of a frame with a pose and a BA covariance (pose_valid,
// T_w_c_covariance_valid); false otherwise (e.g. the first frame of a map, a relocalized one).
bool stepCovariance(const FrameResult& result, Eigen::Matrix<double, 6, 6>* covariance,
                    const StepCovarianceModel& model = {});
// The same for a pose announced before its frame's map work (System::PoseListener).
bool stepCovariance(const FramePose& pose, Eigen::Matrix<double, 6, 6>* covariance,
                    const StepCovarianceModel& model = {});

}  // namespace vitamin_e::pipeline
