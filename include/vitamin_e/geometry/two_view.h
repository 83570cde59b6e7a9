#pragma once
// Two-view initialization from normalized correspondences (undistorted x/z, y/z).
//
// Method: 5-point essential matrix in RANSAC (cv::findEssentialMat with an identity camera
// matrix; the pixel threshold is divided by focal_px), pose by a cheirality vote over the four
// decompositions (cv::recoverPose's choice, with a 2x2 least-squares depth per point instead of
// its SVD), DLT + Gauss-Newton triangulation of every inlier, then checks.
// Planar scenes: the essential matrix of a plane is not unique. Besides the true motion, a
// 'twisted' one (roughly along the plane normal, rotated by a few degrees) explains every
// correspondence, and RANSAC returns either; under the twisted one about half of the points
// triangulate behind a camera. So when a homography explains most essential inliers
// (planar_min_ratio), its decompositions (cv::decomposeHomographyMat) join the essential
// motion as candidates, and the candidate with the most points in front of both cameras
// (and within max_reproj_error_px) wins if it beats the essential motion clearly
// (homography_min_gain); otherwise the essential motion is kept. A result with fewer
// than min_valid_ratio of the inliers in front is refused; one where a different motion does
// nearly as well is flagged ambiguous (or refused, refuse_ambiguous). Degeneracy: a rotation-only model (x1 ~ R x0, i.e. the homography of a pure
// rotation, fitted to the essential inliers) is compared with the essential model; when it
// explains nearly as many correspondences (rotation_only_max_ratio) or the median parallax is
// below min_parallax_deg, the result is ok=false with a reason: no map is ever built from a
// pure rotation.
//
// SCALE: monocular, so the scale is arbitrary. It is fixed so that the MEDIAN DEPTH (z in
// camera 0) of the valid points_c0 is 1; T_c1_c0.translation() is scaled accordingly.
// T_c1_c0 maps camera-0 coordinates to camera-1 coordinates (camera 0 is the origin).
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

namespace vitamin_e {
namespace geometry {

struct TwoViewConfig {
  double ransac_threshold_px = 1.0;  // epipolar (Sampson) threshold of RANSAC, pixels
  double focal_px = 450.0;           // converts pixel thresholds to normalized units
  double min_parallax_deg = 1.0;     // median parallax of the triangulated points
  double min_inlier_ratio = 0.5;     // essential-matrix inliers / correspondences
  int min_points = 50;               // valid triangulated points
  double confidence = 0.999;
  int max_iterations = 1000;
  double max_reproj_error_px = 2.0;      // per triangulated point, both views
  double point_min_parallax_deg = 0.05;  // points below this are kept invalid (near infinity)
  double rotation_only_max_ratio = 0.9;  // refuse if rotation-only inliers >= this * essential inliers
  // Planar scenes (see the header comment): when a homography explains at least
  // planar_min_ratio of the essential inliers (> 1: never tested), its motions compete with the
  // essential one on the number of points triangulated in front of both cameras.
  double planar_min_ratio = 0.8;
  // A homography motion replaces the essential one only if it triangulates at least
  // (1 + this) times as many points in front of both cameras (the twisted motion: about 2x).
  double homography_min_gain = 0.2;
  double planar_distinct_deg = 30.0;   // translations further apart than this are different motions
  double ambiguous_rival_ratio = 0.9;  // ambiguous if a different motion triangulates >= this * the best's points
  bool refuse_ambiguous = false;       // true: an ambiguous result is refused (ok=false); false: flagged only
  // Refuse if fewer than this * essential inliers triangulate in front of both cameras. The
  // twisted motion of a plane puts about half of them behind a camera (47-54 % in front
  // measured); the true motion, 99.8-100 % in the synthetic tests.
  double min_valid_ratio = 0.6;
  void validate() const;  // throws std::invalid_argument naming the key
};

struct TwoViewResult {
  bool ok = false;
  std::string reason;  // empty when ok
  Eigen::Isometry3d T_c1_c0 = Eigen::Isometry3d::Identity();
  std::vector<Eigen::Vector3d> points_c0;  // per correspondence, in camera 0 (valid only where valid[i])
  std::vector<bool> valid;
  double median_parallax_deg = 0.0;
  int num_inliers = 0;                // valid triangulated points
  int num_essential_inliers = 0;      // RANSAC inliers of the essential matrix
  int num_rotation_only_inliers = 0;  // inliers of the rotation-only model
  int num_homography_inliers = 0;     // essential inliers a homography explains
  bool planar = false;                // num_homography_inliers >= planar_min_ratio * essential inliers
  bool used_homography = false;       // the motion came from the homography, not the essential matrix
  int num_rival_inliers = 0;          // valid points of the best different motion (0: none)
  // A different motion (translation > planar_distinct_deg away) triangulates nearly as many
  // points (ambiguous_rival_ratio): two views cannot tell which is right. The result is the
  // essential matrix's choice unless refuse_ambiguous.
  bool ambiguous = false;
};

TwoViewResult initializeTwoView(const std::vector<Eigen::Vector2d>& xy0, const std::vector<Eigen::Vector2d>& xy1,
                                const TwoViewConfig& config);

// Rotation-only model: least-squares R with bearing(x1) ~ R bearing(x0) (Kabsch on unit
// bearings, over mask, empty = all). Returns R_c1_c0.
Eigen::Matrix3d fitRotationOnly(const std::vector<Eigen::Vector2d>& xy0, const std::vector<Eigen::Vector2d>& xy1,
                                const std::vector<bool>& mask);

}  // namespace geometry
}  // namespace vitamin_e
