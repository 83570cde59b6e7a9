#pragma once
// The back end: bundle adjustment on every frame (subspace Gauss-Newton; the
// frame's camera and the points it sees), keyframes by parallax, triangulation
// of new tracks, and the keyframe window BA. Works on the Map through its
// interface; landmarks it removes are returned so that their tracks can end.
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "vitamin_e/camera/camera.h"
#include "vitamin_e/map/map.h"
#include "vitamin_e/pipeline/frame_context.h"
#include "vitamin_e/pipeline/system_config.h"

namespace vitamin_e::pipeline {

struct FrameRefinement {
  std::vector<std::uint64_t> removed;  // landmarks removed as outliers (their tracks must end)
  // The frame's pose covariance (optimization::BaSummary::camera_covariance, right perturbation).
  Eigen::Matrix<double, 6, 6> covariance = Eigen::Matrix<double, 6, 6>::Zero();
  bool covariance_valid = false;
};

struct KeyframeDecision {
  bool needed = false;
  double parallax_px = 0.0;  // rotation-compensated median parallax to the last keyframe [px]
};

struct KeyframeUpdate {
  Eigen::Isometry3d T_w_c = Eigen::Isometry3d::Identity();  // the new keyframe's pose after the window BA
  int triangulated = 0;                                     // new landmarks
  std::map<std::string, int> rejected_by;                   // tracks tried but not triangulated, by the failed check:
                                                            // "parallax", "reprojection", "cheirality", "other"
  std::vector<std::uint64_t> removed;                       // landmarks removed as outliers (their tracks must end)
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

  // Per-frame BA: the frame's camera and the points it sees are free, the
  // keyframes fixed. Updates *T_w_c and the points; returns the removed
  // landmarks and the pose's covariance.
  FrameRefinement refineFrame(const FrameContext& frame, Eigen::Isometry3d* T_w_c, map::Map* map) const;
  // Keyframe BA over the window (the newest keyframes free, the oldest fixed).
  std::vector<std::uint64_t> optimizeWindow(map::Map* map) const;
  KeyframeDecision needKeyframe(const FrameContext& frame, const Eigen::Isometry3d& T_w_c, const map::Map& map) const;
  // Inserts the frame as a keyframe, triangulates its unmapped tracks and runs
  // the window BA. frame->landmarks is looked up again.
  KeyframeUpdate addKeyframe(FrameContext* frame, const Eigen::Isometry3d& T_w_c, map::Map* map) const;
  // The frame's candidates for triangulation at pose T_w_c (a diagnostic; reads only).
  TriangulationBacklog backlog(const FrameContext& frame, const Eigen::Isometry3d& T_w_c, const map::Map& map) const;
  // Counts one more offence for each landmark; removes those at the limit
  // (pipeline.max_outlier_count) and returns their ids.
  std::vector<std::uint64_t> penalize(const std::vector<std::uint64_t>& ids, map::Map* map) const;
  // Localization only: the map's points are not moved and not deleted. The
  // per-frame BA refines the camera alone, and a point at the outlier limit is
  // detached from its track (kept as a dormant point) instead of removed.
  void setLocalizationOnly(bool on) { localization_only_ = on; }

 private:
  FrameRefinement bundleAdjust(const FrameContext* frame, Eigen::Isometry3d* T_w_c, map::Map* map) const;
  int triangulate(const FrameContext& frame, map::Map* map, std::map<std::string, int>* rejected_by) const;

  SystemConfig config_;
  camera::Camera camera_;
  bool localization_only_ = false;
};

}  // namespace vitamin_e::pipeline
