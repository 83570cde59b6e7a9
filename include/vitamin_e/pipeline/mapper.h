#pragma once
// The back end: bundle adjustment on every frame (subspace Gauss-Newton; the
// frame's camera and the points it sees), keyframes by parallax, triangulation
// of new tracks, and the keyframe window BA. Reads the Map; what it would change
// comes back as values (a MapUpdate, new landmarks) that System applies.
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "vitamin_e/camera/camera.h"
#include "vitamin_e/map/map.h"
#include "vitamin_e/pipeline/frame_context.h"
#include "vitamin_e/pipeline/map_update.h"
#include "vitamin_e/pipeline/system_config.h"

namespace vitamin_e::pipeline {

struct FrameRefinement {
  Eigen::Isometry3d T_w_c = Eigen::Isometry3d::Identity();  // the frame's pose after the BA
  MapUpdate update;                                         // the points moved, the offenders
  // The frame's pose covariance (optimization::BaSummary::camera_covariance, right perturbation).
  Eigen::Matrix<double, 6, 6> covariance = Eigen::Matrix<double, 6, 6>::Zero();
  bool covariance_valid = false;
};

struct KeyframeDecision {
  bool needed = false;
  double parallax_px = 0.0;  // rotation-compensated median parallax to the last keyframe [px]
};

// New landmarks from the frame's unmapped tracks, and why the others were refused.
struct Triangulation {
  std::vector<map::NewLandmark> landmarks;
  std::map<std::string, int> rejected_by;  // tracks tried but not triangulated, by the failed check:
                                           // "parallax", "reprojection", "cheirality", "other"
};

// The unmapped tracks of a frame that a keyframe older than the frame saw
// since the track was detected: the points waiting for triangulation.
struct TriangulationBacklog {
  std::size_t candidates = 0;
  std::size_t seen_twice = 0;        // of them also seen by the newest keyframe (two or more keyframes)
  double median_parallax_deg = 0.0;  // of the angle between the ray of the first keyframe seeing it and the frame's
};

class Mapper {
 public:
  Mapper(const SystemConfig& config, const camera::Camera& camera);

  // Per-frame BA: the frame's camera (at T_w_c) and the points it sees are
  // free, the keyframes fixed.
  FrameRefinement refineFrame(const FrameContext& frame, const Eigen::Isometry3d& T_w_c, const map::Map& map) const;
  // Keyframe BA over the window (the newest keyframes free, the oldest fixed).
  MapUpdate optimizeWindow(const map::Map& map) const;
  KeyframeDecision needKeyframe(const FrameContext& frame, const Eigen::Isometry3d& T_w_c, const map::Map& map) const;
  // The frame as a keyframe at T_w_c: every track's observation.
  static map::Keyframe keyframeOf(const FrameContext& frame, const Eigen::Isometry3d& T_w_c);
  // Triangulates the frame's unmapped tracks from the keyframes that saw them
  // (the frame's own keyframe among them: call after adding it).
  Triangulation triangulate(const FrameContext& frame, const map::Map& map) const;
  // The frame's candidates for triangulation at pose T_w_c (a diagnostic).
  TriangulationBacklog backlog(const FrameContext& frame, const Eigen::Isometry3d& T_w_c, const map::Map& map) const;
  // Localization only: the map's points are not moved. The per-frame BA
  // refines the camera alone (and applyMapUpdate detaches offenders instead of
  // removing them: OffencePolicy).
  void setLocalizationOnly(bool on) { localization_only_ = on; }

 private:
  // frame == null: the keyframe window BA; otherwise the per-frame BA of frame at T_w_c.
  FrameRefinement bundleAdjust(const FrameContext* frame, const Eigen::Isometry3d& T_w_c, const map::Map& map) const;

  SystemConfig config_;
  camera::Camera camera_;
  bool localization_only_ = false;
};

}  // namespace vitamin_e::pipeline
