#pragma once
// Synthetic bundle-adjustment scenes for tests and benchmarks: cameras along a gently curving
// trajectory looking forward (+z), points each tracked over a run of consecutive cameras
// (like per-frame feature tracks), observations with Gaussian pixel noise and a fraction of
// gross outliers.
#include <vector>

#include "vitamin_e/optimization/ba_problem.h"

namespace vitamin_e {
namespace optimization {

struct SyntheticBaConfig {
  int num_cameras = 10;
  int num_points = 1000;
  camera::Pinhole K{450.0, 450.0, 320.0, 240.0};
  int width = 640, height = 480;
  double step_m = 0.1;                      // distance between consecutive cameras
  double min_depth = 3.0, max_depth = 8.0;  // point depth in its reference camera
  int min_track = 3, max_track = 10;        // consecutive cameras observing a point
  double noise_px = 1.0;                    // per coordinate, Gaussian
  double outlier_ratio = 0.05;
  double outlier_min_px = 10.0, outlier_max_px = 50.0;
  unsigned seed = 1;
  void validate() const;  // throws std::invalid_argument naming the key
};

struct SyntheticBa {
  BaProblem truth;                             // true cameras and points, noise-free observations
  BaProblem noisy;                             // true cameras and points, noisy observations (with outliers)
  std::vector<bool> outlier;                   // per observation
  std::vector<int> first_camera, last_camera;  // per point: its track
};

SyntheticBa makeSyntheticBa(const SyntheticBaConfig& config);

// Perturbs the non-fixed cameras (rotation about a random axis by N(0, rot_deg), translation
// N(0, trans_m) per axis) and non-fixed points (N(0, point_m) per axis).
void perturbBaProblem(BaProblem* problem, double rot_deg, double trans_m, double point_m, unsigned seed);

// RMS of the camera position errors |t_est - t_true| over the cameras selected by mask
// (empty = all).
double cameraPositionRmse(const BaProblem& estimate, const BaProblem& truth, const std::vector<bool>& mask = {});

}  // namespace optimization
}  // namespace vitamin_e
