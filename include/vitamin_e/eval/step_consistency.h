#pragma once
// Is a pose covariance an honest account of the error? For each step between two
// consecutive estimated poses (the frame-to-frame motion, what an odometry filter
// uses), the normalized estimation error squared (NEES) of the step against the
// ground truth, with the step's covariance as the estimate reports it. A consistent
// covariance gives NEES values distributed as chi-square with 6 degrees of freedom:
// their mean lies within the chi-square bounds of the mean of that many draws.
//
// Monocular poses are in map units (arbitrary scale): each ground-truth step is brought
// into map units by the local scale, the ratio of the estimated and the true path lengths
// over the steps around it (a scale drift is not an error of one step).
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "vitamin_e/eval/trajectory.h"

namespace vitamin_e::eval {

using Matrix6d = Eigen::Matrix<double, 6, 6>;

// An estimated pose with the covariance of its step from the previous pose: the right
// perturbation delta = (rho, phi) of the step, T_prev^-1 T = (true step) * expSE3(delta),
// i.e. in the camera frame of this pose; map units^2 and rad^2.
struct StepEstimate {
  double t = 0.0;
  Eigen::Isometry3d T_w_c = Eigen::Isometry3d::Identity();
  Matrix6d step_covariance = Matrix6d::Zero();
  bool has_covariance = false;  // the first pose of a run has none
};

struct StepConsistencyOptions {
  double max_dt = 0.02;   // association with the ground truth [s]
  int scale_window = 10;  // steps on each side for the local scale
};

struct StepConsistency {
  int steps = 0;                    // steps with a covariance and ground truth on both ends
  double mean_nees = 0.0;           // expected 6
  double lower = 0.0, upper = 0.0;  // 95 % bounds of the mean of `steps` chi-square(6) draws
  double mean_nees_position = 0.0;  // of the translation part alone (expected 3)
  double mean_nees_rotation = 0.0;  // of the rotation part alone (expected 3)
  double median_nees = 0.0;
  double fraction_within_95 = 0.0;                  // steps with NEES below chi-square(6)'s 95 % point (12.59)
  std::vector<double> nees;                         // per step, in order
  std::vector<double> stamps;                       // of the step's end
  std::vector<Eigen::Matrix<double, 6, 1>> errors;  // delta of each step (rho, phi), map units and rad
  bool consistent() const { return steps > 0 && mean_nees >= lower && mean_nees <= upper; }
};

// Throws std::invalid_argument when fewer than two poses match the ground truth.
StepConsistency stepConsistency(const std::vector<StepEstimate>& estimate, const Trajectory& ground_truth,
                                const StepConsistencyOptions& options = {});

// Quantile of chi-square with k degrees of freedom (Wilson-Hilferty; within 0.5 % for k >= 6).
double chiSquareQuantile(double p, double k);

}  // namespace vitamin_e::eval
