#pragma once
// The road under a camera mounted on a ground vehicle: a plane fitted to 3D points
// given in the camera frame (x right, y down, z forward), by RANSAC over the
// points below the camera whose normal stays within max_tilt_deg of the camera's
// down axis (the camera is mounted roughly level), then refined by least squares
// on the inliers. The camera's height above it is the distance from the camera
// centre to the plane: a car's camera keeps it, so it measures the map's scale.
#include <Eigen/Core>
#include <vector>

namespace vitamin_e {
namespace geometry {

struct GroundPlaneConfig {
  double max_tilt_deg = 15.0;        // angle between the plane's normal and the camera's y axis
  double min_depression_deg = 4.0;   // a candidate is at least this far below the optical axis' horizon
  double inlier_ratio = 0.03;        // inlier: distance to the plane below this x the camera height
  int min_inliers = 100;             // fewer: no plane
  double min_inlier_fraction = 0.3;  // of the candidates, fewer: no plane (a kerb, a car, clutter)
  int iterations = 200;              // RANSAC samples (deterministic: a fixed seed)
  void validate() const;             // throws std::invalid_argument naming the key
};

struct GroundPlane {
  bool valid = false;
  double height = 0.0;                                  // camera centre to the plane, in the points' units
  Eigen::Vector3d normal_c = Eigen::Vector3d::UnitY();  // unit, pointing away from the camera (down)
  int candidates = 0;                                   // points below the camera that were considered
  int inliers = 0;
};

GroundPlane fitGroundPlane(const std::vector<Eigen::Vector3d>& points_c, const GroundPlaneConfig& config);

}  // namespace geometry
}  // namespace vitamin_e
