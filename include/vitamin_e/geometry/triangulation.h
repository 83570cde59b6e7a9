#pragma once
// Multi-view triangulation of one point from camera poses T_w_c and normalized observations
// (undistorted x/z, y/z): linear DLT, then Gauss-Newton on the reprojection error in
// normalized coordinates (errors are reported in pixels via focal_px).
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

namespace vitamin_e {
namespace geometry {

struct TriangulationConfig {
  double focal_px = 450.0;           // converts normalized errors to pixels
  double min_parallax_deg = 1.0;     // largest angle between two viewing rays must reach this
  double max_reproj_error_px = 2.0;  // every view must reproject within this
  double min_depth = 1e-6;           // cheirality: depth in every camera must exceed this
  int gn_iterations = 10;
  void validate() const;  // throws std::invalid_argument naming the key
};

// The check a triangulation failed, in the order they are made.
enum class TriangulationCheck {
  kNone,          // ok
  kViews,         // fewer than two views, or observations not one per view
  kLinear,        // the linear solution is at infinity
  kCheirality,    // behind a camera
  kParallax,      // the rays' widest angle is below min_parallax_deg
  kReprojection,  // a view reprojects beyond max_reproj_error_px
};

struct TriangulationResult {
  bool ok = false;
  TriangulationCheck failed = TriangulationCheck::kNone;
  std::string reason;  // the failed check in words; empty when ok
  Eigen::Vector3d p_w = Eigen::Vector3d::Zero();
  double parallax_deg = 0.0;            // largest angle between two viewing rays at p_w
  std::vector<double> reproj_error_px;  // per view, at p_w
  bool cheirality_ok = false;           // in front of every camera
};

// T_w_c[k] and xy[k] describe view k (at least two views). Returns the point even when a check
// fails (ok=false, reason says which) as long as the linear system was solvable.
TriangulationResult triangulatePoint(const std::vector<Eigen::Isometry3d>& T_w_c,
                                     const std::vector<Eigen::Vector2d>& xy, const TriangulationConfig& config);

// Linear DLT only (homogeneous SVD of the 2n x 4 system). Returns false when the point is at
// infinity (homogeneous w ~ 0).
bool triangulateDlt(const std::vector<Eigen::Isometry3d>& T_w_c, const std::vector<Eigen::Vector2d>& xy,
                    Eigen::Vector3d* p_w);

// Angle in degrees between the rays from two camera centers to p_w.
double parallaxDeg(const Eigen::Vector3d& center_a, const Eigen::Vector3d& center_b, const Eigen::Vector3d& p_w);

}  // namespace geometry
}  // namespace vitamin_e
