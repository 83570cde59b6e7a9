#pragma once
// Scale from the road (ground vehicles). A monocular map's scale drifts where
// the camera turns faster than it travels: the translation is then the small
// remainder of a large rotational image motion, and a calibration error of a
// pixel or a per cent, which every real camera has, biases it (KITTI 07's first
// turn: +20 % in 2 s). A camera on a car keeps its height above the road, so at
// each keyframe the road plane under the camera (geometry::fitGroundPlane on the
// frame's map points) measures the map's scale; the map is held to the height of
// its first keyframes that agree by scaling it, a little at a time, about the camera.
// Off by default: a drone or a hand-held camera has no constant height.
#include <vector>

#include <Eigen/Core>

#include "vitamin_e/geometry/ground_plane.h"

namespace vitamin_e::pipeline {

struct GroundScaleConfig {
  bool enabled = false;
  geometry::GroundPlaneConfig plane;
  // Road points needed for a measurement, as a share of the point budget (tracker.max_points):
  // the system sets plane.min_inliers from it.
  double min_inlier_budget_fraction = 0.0125;
  // Faster than this x the camera height per frame, the road's near points are lost to the
  // image motion and the far ones, triangulated with little parallax, bias the plane: no measurement.
  double max_step_height_ratio = 0.5;
  // The first this many consecutive keyframes with a road plane whose heights agree (each within
  // max_change of their median) set the height: their median.
  int reference_keyframes = 3;
  int window = 5;           // the map's height is the median of the last this many measurements
  double tolerance = 0.05;  // a scale error within this share is measurement noise: no correction
  // The tolerance grows by this x the window's own spread (the median of its heights' relative
  // deviations from their median): measurements that disagree among themselves (a plane that
  // caught a kerb for a few keyframes) must be further off before they correct (0: fixed tolerance).
  double spread_factor = 0.5;
  double gain = 0.5;        // share of the scale error beyond the tolerance corrected per keyframe, (0, 1]
  double max_change = 0.1;  // a height off the map's current one by more than this share is not the road: ignored
                            // (unless `window` consecutive ones agree among themselves: the map's scale moved)
  void validate() const;    // throws std::invalid_argument naming the key
};

// One keyframe's measurement and what it did.
struct ScaleCorrection {
  bool measured = false;   // a road plane was found
  double height = 0.0;     // camera height above it, map units (before the correction)
  int inliers = 0;         // road points of the plane
  double reference = 0.0;  // the height the map is held to (0: not set yet)
  double factor = 1.0;     // scale the map by this about the camera centre (1: unchanged)
};

class GroundScale {
 public:
  explicit GroundScale(const GroundScaleConfig& config);
  bool enabled() const { return config_.enabled; }
  // points_c: the keyframe's map points in its camera frame; step: the camera's last
  // frame-to-frame translation (map units).
  ScaleCorrection update(const std::vector<Eigen::Vector3d>& points_c, double step);
  void reset();  // a new map: its own scale, a new reference

 private:
  GroundScaleConfig config_;
  std::vector<double> first_heights_;
  std::vector<double> recent_;    // the last `window` accepted heights, in the current scale
  std::vector<double> rejected_;  // consecutive heights off the map's current one (at most `window`)
  double reference_ = 0.0;
};

}  // namespace vitamin_e::pipeline
