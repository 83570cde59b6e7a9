#pragma once
// The fields of SystemConfig (see system_config.h). Each component keeps its own
// Config struct; the pipeline's own parameters follow, with their defaults.
#include <string>

#include "vitamin_e/fusion/dense_mapper.h"
#include "vitamin_e/geometry/pnp.h"
#include "vitamin_e/geometry/triangulation.h"
#include "vitamin_e/geometry/two_view.h"
#include "vitamin_e/map/map.h"
#include "vitamin_e/optimization/subspace_gn.h"
#include "vitamin_e/pipeline/ground_scale.h"
#include "vitamin_e/pipeline/relocalizer.h"
#include "vitamin_e/tracking/dense_tracker.h"

namespace vitamin_e::pipeline {

// Dense reconstruction defaults for a monocular map, whose unit is the median
// scene depth at initialization (voxels of 2% of it, truncation 5 voxels).
fusion::DenseMapperConfig defaultDenseConfig();

// The dense tracker as validated with the SLAM on the renders and the real clips (the
// tracker's own defaults are those of its standalone tests): a weaker flow prior and no
// patch confirmation of the climb (the pose's RANSAC and BA reject what the confirmation
// would; TrackSurvival tells a cut from the survival of the map tracks instead).
tracking::TrackerConfig defaultTrackerConfig();

// Floors of the counts that follow the point budget: an essential matrix needs 8 tracks to be
// tried, a plane 3 points.
constexpr int kMinInitTracksFloor = 8;
constexpr int kMinRoadInliersFloor = 3;

struct SystemConfig {
  tracking::TrackerConfig tracker = defaultTrackerConfig();  // yaml section "tracker"
  geometry::TwoViewConfig init;                              // yaml section "init"
  geometry::PnpConfig pnp;                                   // yaml section "pnp"
  geometry::TriangulationConfig triangulation;               // yaml section "triangulation"
  optimization::BaOptions ba;                                // yaml section "ba"
  map::MapConfig map;                                        // yaml section "map"
  RelocalizerConfig relocalization;                          // yaml section "relocalization"
  GroundScaleConfig ground;                                  // yaml section "ground"
  // Dense reconstruction (yaml section "dense"): run by the offline runner and
  // the ROS meshing nodelet on the system's per-frame points, not by System.
  bool dense_enabled = true;
  fusion::DenseMapperConfig dense = defaultDenseConfig();

  // --- pipeline (yaml section "pipeline") ---
  // Tracks shared with the reference frame needed to try initializing, as a share of the point
  // budget (tracker.max_points): a camera tracking fewer points asks for fewer.
  double min_init_track_budget_fraction = 0.025;
  int min_init_tracks = 200;  // set by the system: the fraction x tracker.max_points, at least kMinInitTracksFloor
  double init_min_disparity_px = 20.0;        // median track displacement before the two-view fit is tried
  int init_max_pending_frames = 60;           // frames kept since the reference; beyond it the reference moves on
  int min_pose_inliers = 30;                  // fewer P3P inliers than this: the frame is lost
  double min_pose_inlier_ratio = 0.5;         // ... or fewer than this share of the tracked map points
  double weak_pose_max_step_ratio = 2.0;      // ... unless its step is within this factor of the predicted one
  double weak_pose_min_survival_ratio = 0.5;  // ... and the last frame's map tracks survived at least this
                                              // share of the usual (median of the last 10 frames)
  bool keyframe_on_weak_pose = true;          // false: a frame whose weak pose was kept makes no keyframe
  int max_outlier_count = 2;                  // times a point may be an outlier before it is removed
  double max_reprojection_px = 3.0;           // observation residual after BA above which a point is flagged
  int ba_fixed_keyframes = 2;                 // oldest keyframes held fixed in the keyframe BA (gauge and scale)
  int ba_keyframe_sweeps = 5;                 // subspace GN sweeps when a keyframe is inserted
  int ba_frame_sweeps = 3;                    // subspace GN sweeps of the per-frame BA
  int ba_free_keyframes = 4;                  // newest keyframes optimized by the keyframe BA (with their points)
  bool defer_keyframe_ba = true;              // a keyframe that reaches the mapper while the next frame already
                                              // waits for it (PipelinedSystem, live) leaves its window BA to the
                                              // next keyframe, never two in a row; sequential mode never waits
  double ba_free_min_shared = 0.0;            // experimental, 0 = off; > 0: instead, free every keyframe that sees at
                                              // least this share of the newest keyframe's map points (never the gauge)
  double keyframe_parallax_px = 20.0;         // rotation-compensated median parallax to the last keyframe
  double keyframe_min_mapped_ratio = 0.5;     // fewer mapped tracks than this ratio also asks for a keyframe
  double max_step_depth_ratio = 1.0;          // a per-frame step longer than this x scene depth is a failure
  // Map reuse: a new, unmapped track within reuse_radius_px of the projection of a
  // map point whose own track ended (still in the window, or dormant: see
  // map.max_dormant_landmarks) takes that point over, when the curvature signs
  // agree, no other track is nearer, and nothing in view is clearly in front of
  // it. 0 turns map reuse off.
  double reuse_radius_px = 2.0;
  double reuse_occlusion_ratio = 1.2;   // farther than this x the nearest mapped depth around it: occluded
  bool reuse_fix_revived = true;        // revived dormant points stay fixed in BA (they anchor the older map)
  int reuse_dormant_per_frame = 25000;  // dormant points checked per frame, round robin (bounds the cost)

  void validate() const;         // throws ConfigError naming the key
  std::string describe() const;  // readable listing of every value
};

}  // namespace vitamin_e::pipeline
