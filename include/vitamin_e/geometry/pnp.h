#pragma once
// Camera pose from 3D world points and their normalized observations (undistorted x/z, y/z).
// Either (a) a pose guess (e.g. from a motion model) is checked and, when enough points agree
// with it, refined directly; or (b) AP3P inside RANSAC (cv::solvePnPRansac) gives a pose and
// inlier set. The pose is then refined by Gauss-Newton with the Geman-McClure kernel (IRLS)
// on the inliers, and inliers are re-classified with ransac_threshold_px.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

namespace vitamin_e {
namespace geometry {

struct PnpConfig {
  double focal_px = 450.0;           // converts pixel thresholds to normalized units
  double ransac_threshold_px = 2.0;  // inlier threshold (reprojection error, pixels)
  double confidence = 0.999;
  int max_iterations = 200;  // RANSAC iterations
  int min_inliers = 12;
  double min_inlier_ratio = 0.2;  // of the input correspondences
  double robust_sigma_px = 2.0;   // Geman-McClure sigma of the refinement
  int refine_iterations = 10;
  double guess_min_inlier_ratio = 0.6;  // the guess is used directly when this many agree
  void validate() const;                // throws std::invalid_argument naming the key
};

struct PnpResult {
  bool ok = false;
  std::string reason;  // empty when ok
  Eigen::Isometry3d T_w_c = Eigen::Isometry3d::Identity();
  std::vector<bool> inliers;  // per input correspondence
  int num_inliers = 0;
  bool used_guess = false;  // the guess was good and RANSAC was skipped
};

PnpResult solvePnpRansac(const std::vector<Eigen::Vector3d>& p_w, const std::vector<Eigen::Vector2d>& xy,
                         const PnpConfig& config, const Eigen::Isometry3d* T_w_c_guess = nullptr);

// Gauss-Newton refinement of T_w_c with the Geman-McClure kernel on the selected points
// (mask may be empty = all). Residuals in pixels (normalized * focal_px). Returns the final
// robust cost.
double refinePoseGemanMcClure(const std::vector<Eigen::Vector3d>& p_w, const std::vector<Eigen::Vector2d>& xy,
                              const std::vector<bool>& mask, double focal_px, double sigma_px, int iterations,
                              Eigen::Isometry3d* T_w_c);

}  // namespace geometry
}  // namespace vitamin_e
