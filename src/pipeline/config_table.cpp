// The configuration table: every member of every config struct the SLAM uses,
// as a yaml key with a one-line description, or marked as set internally.
// Keep the descriptions in step with the struct comments; regenerate
// docs/CONFIG.md (vitamin_e_run --print-config-markdown) after a change.
#include "config_table.h"

namespace vitamin_e::pipeline::detail {

namespace {

const char* const kFocal = "the camera's focal length, (fx + fy) / 2: converts the pixel thresholds";

}  // namespace

std::vector<Field> configTable(SystemConfig& c) {
  Table t;
  // --- tracker ---
  t.section("tracker");
  auto& tk = c.tracker;
  t.key("max_points", &tk.max_points, "upper bound on live points per frame (> 0)");
  t.key("grid_cell_px", &tk.grid_cell_px, "bucketing cell [px]: new points go to under-filled cells");
  t.key("max_per_cell", &tk.max_per_cell, "live points allowed per cell (>= 1)");
  t.key("nms_radius_px", &tk.nms_radius_px, "an extremum must dominate its (2r+1)^2 window, same sign (>= 1)");
  t.key("border_px", &tk.border_px, "no point closer than this to the image border [px] (>= 2)");
  t.key("smoothing_sigma", &tk.smoothing_sigma, "Gaussian pre-smoothing before the derivatives [px] (0 = none)");
  t.key("adaptive_smoothing", &tk.adaptive_smoothing,
        "raise the smoothing on noisy images (noise / median gradient above noise_reference)");
  t.key("max_smoothing_sigma", &tk.max_smoothing_sigma,
        "upper bound of the adaptive smoothing [px] (>= smoothing_sigma)");
  t.key("noise_reference", &tk.noise_reference,
        "noise sigma / median raw gradient above which the smoothing grows as sqrt(ratio / this) (> 0)");
  t.key("kappa_smoothing_sigma", &tk.kappa_smoothing_sigma,
        "Gaussian smoothing of kappa itself before extrema and tracking [px] (0 = none)");
  t.key("min_curvature", &tk.min_curvature, "detection threshold on abs(kappa) / median abs(kappa) (>= 0)");
  t.key("min_abs_curvature", &tk.min_abs_curvature,
        "absolute floor on abs(kappa) [DN^3/px^4]: flat or black images give no points");
  t.key("brief_scale", &tk.brief_scale, "dominant flow: shrink factor of the BRIEF matching image, (0, 1]");
  t.key("brief_max_keypoints", &tk.brief_max_keypoints, "strongest curvature extrema of the small image described");
  t.key("brief_patch_size", &tk.brief_patch_size, "BRIEF test window in the small image [px], odd >= 7");
  t.key("brief_max_distance", &tk.brief_max_distance, "largest Hamming distance of an accepted match (of 256)");
  t.key("brief_ratio", &tk.brief_ratio,
        "best / second-best distance ratio test, (0, 1]; matches are also cross-checked");
  t.key("flow_sigma_px", &tk.flow_sigma_px, "final Geman-McClure sigma of the affine flow fit [full-resolution px]");
  t.key("flow_sigma_start_px", &tk.flow_sigma_start_px,
        "the fit's annealing starts here and halves down to flow_sigma_px (>= flow_sigma_px)");
  t.key("flow_iterations", &tk.flow_iterations, "IRLS iterations per annealing level (>= 1)");
  t.key("flow_min_matches", &tk.flow_min_matches,
        "fewer inliers than this: no flow for the frame (identity and the previous translation are used)");
  t.key("lambda", &tk.lambda, "weight of the flow prediction in the hill climbing, in normalized-curvature units");
  t.key("track_sigma_px", &tk.track_sigma_px, "Geman-McClure sigma of the prediction's weight [px] (> 0)");
  t.key("max_climb_steps", &tk.max_climb_steps, "hill-climbing steps (8-neighbour moves) before giving up (>= 1)");
  t.key("prediction_blend", &tk.prediction_blend,
        "[0, 1): moves the sub-pixel extremum this far toward the prediction when within 1 px (where the patch "
        "filter, extremum_weight < 1, does not apply)");
  t.key("polish_steps", &tk.polish_steps, "after the climb, steps climbing kappa alone, without the prior (0 = off)");
  t.key("fb_threshold_px", &tk.fb_threshold_px,
        "forward-backward check: largest distance back to the old position [px]");
  t.key("min_track_curvature", &tk.min_track_curvature, "a track ends when its normalized kappa falls below this");
  t.key("max_curvature_ratio", &tk.max_curvature_ratio,
        "... or when its normalized abs(kappa) changes by more than this factor (>= 1)");
  t.key("relative_strength_change", &tk.relative_strength_change,
        "... measured relative to the frame's median change over the climbed tracks (exposure steps); false: to 1");
  t.key("strength_ratio_min_change", &tk.strength_ratio_min_change,
        "... when that median change leaves [1/(1+this), 1+this]; within it, against 1 (>= 0)");
  t.key("floor_follows_exposure", &tk.floor_follows_exposure,
        "for a tracked point, min_abs_curvature follows the frames' common curvature change since its detection");
  t.key("min_track_sharpness", &tk.min_track_sharpness,
        "... or when the kappa peak it climbed to is flatter than this [1/px^2] (0 = off)");
  t.key("strength_at_subpixel_peak", &tk.strength_at_subpixel_peak,
        "those checks use the fitted sub-pixel peak (true) or kappa at the integer maximum (false)");
  t.key("extremum_weight", &tk.extremum_weight,
        "(0, 1]: position = patch-aligned previous position + this x (extremum - it); 1 = the extremum alone");
  t.key("align_radius_px", &tk.align_radius_px, "patch of that alignment: (2r+1)^2 px, r in [1, 4]");
  t.key("align_iterations", &tk.align_iterations, "Gauss-Newton steps of the patch alignment (>= 1)");
  t.key("align_gain", &tk.align_gain,
        "the patch alignment fits a contrast gain too on frames whose contrast changed (exposure steps)");
  t.key("align_gain_min_change", &tk.align_gain_min_change,
        "... by more than this fraction (cube root of the median peak ratio); 0 = on every frame (>= 0)");
  t.key("max_align_disagreement_px", &tk.max_align_disagreement_px,
        "a track ends when a patch alignment from the prediction fails or ends farther than this from the climbed "
        "extremum [px] (0 = off)");
  t.key("confirm_max_unaligned_fraction", &tk.confirm_max_unaligned_fraction,
        "[0, 1]: that check is skipped on a frame where the alignment fails for more than this share of tracks");
  t.key("refine_flow", &tk.refine_flow, "refit the flow to the tracked points and track again from it");
  t.key("predict_parallax", &tk.predict_parallax, "add each point's last residual to the flow prediction");
  t.key("retry_from_prior", &tk.retry_from_prior,
        "a map track the flow lost is tracked again from its map point seen from the predicted pose (corrected "
        "by the BRIEF matches around the map tracks), when that lies outside the flow's inlier band (a second "
        "layer after fast motion or dropped frames)");
  t.key("strength_follows_prior_scale", &tk.strength_follows_prior_scale,
        "a track retried from its prior passes the strength check within a band widened by the size change its "
        "map point's depth predicts (at most 4x); a map track that check ended is retried when that change "
        "exceeds 5 % (large steps toward or away from a point: dropped frames, a fast car)");
  t.key("threads", &tk.threads, "image stripes processed in parallel (1 = serial)");

  // --- init (two-view) ---
  t.section("init");
  auto& in = c.init;
  t.key("ransac_threshold_px", &in.ransac_threshold_px, "epipolar (Sampson) threshold of the RANSAC [px]");
  t.internal("focal_px", &in.focal_px, kFocal);
  t.key("min_parallax_deg", &in.min_parallax_deg, "median parallax of the triangulated points needed [deg]");
  t.key("min_inlier_ratio", &in.min_inlier_ratio, "essential-matrix inliers / shared tracks needed, [0, 1]");
  t.key("min_points", &in.min_points, "valid triangulated points needed (>= 5)");
  t.key("confidence", &in.confidence, "RANSAC confidence, (0, 1)");
  t.key("max_iterations", &in.max_iterations, "RANSAC iterations at most");
  t.key("max_reproj_error_px", &in.max_reproj_error_px, "a point must reproject within this in both views [px]");
  t.key("point_min_parallax_deg", &in.point_min_parallax_deg,
        "points with less parallax stay out (near infinity) [deg]");
  t.key("rotation_only_max_ratio", &in.rotation_only_max_ratio,
        "refused when the rotation-only model has >= this x the essential inliers");
  t.key("planar_min_ratio", &in.planar_min_ratio,
        "homography motions compete when a homography explains this share of the essential inliers (> 1: never)");
  t.key("homography_min_gain", &in.homography_min_gain,
        "a homography motion wins when it puts (1 + this) x as many points in front of both cameras");
  t.key("planar_distinct_deg", &in.planar_distinct_deg,
        "translations further apart than this are different motions [deg]");
  t.key("ambiguous_rival_ratio", &in.ambiguous_rival_ratio,
        "ambiguous when a different motion triangulates >= this x the best one's points");
  t.key("refuse_ambiguous", &in.refuse_ambiguous, "true: an ambiguous initialization is refused; false: only flagged");
  t.key("min_valid_ratio", &in.min_valid_ratio,
        "refused when fewer than this x the essential inliers triangulate in front of both cameras");

  // --- pnp ---
  t.section("pnp");
  auto& pn = c.pnp;
  t.internal("focal_px", &pn.focal_px, kFocal);
  t.key("ransac_threshold_px", &pn.ransac_threshold_px, "inlier threshold on the reprojection error [px]");
  t.key("confidence", &pn.confidence, "RANSAC confidence, (0, 1)");
  t.key("max_iterations", &pn.max_iterations, "RANSAC iterations at most");
  t.key("min_inliers", &pn.min_inliers, "fewer inliers: no pose (>= 4)");
  t.key("min_inlier_ratio", &pn.min_inlier_ratio, "inliers / correspondences needed, [0, 1]");
  t.key("robust_sigma_px", &pn.robust_sigma_px, "Geman-McClure sigma of the pose refinement [px]");
  t.key("refine_iterations", &pn.refine_iterations, "Gauss-Newton iterations of the refinement");
  t.key("guess_min_inlier_ratio", &pn.guess_min_inlier_ratio,
        "the motion model's pose is refined directly, without RANSAC, when this share of the points agrees with it");

  // --- triangulation ---
  t.section("triangulation");
  auto& tr = c.triangulation;
  t.internal("focal_px", &tr.focal_px, kFocal);
  t.key("min_parallax_deg", &tr.min_parallax_deg, "the widest angle between two viewing rays must reach this [deg]");
  t.key("max_reproj_error_px", &tr.max_reproj_error_px, "every keyframe must see the point within this [px]");
  t.key("min_depth", &tr.min_depth, "cheirality: the depth in every camera must exceed this (map units)");
  t.key("gn_iterations", &tr.gn_iterations, "Gauss-Newton iterations after the linear (DLT) solution");

  // --- ba ---
  t.section("ba");
  auto& b = c.ba;
  using Solver = optimization::BaOptions::CameraSolver;
  t.key("robust_sigma_px", &b.robust_sigma_px, "Geman-McClure sigma [px]");
  t.internal("max_sweeps", &b.max_sweeps, "per solve: pipeline.ba_frame_sweeps or pipeline.ba_keyframe_sweeps");
  t.internal(
      "compute_covariance", &b.compute_covariance,
      "the per-frame BA returns the frame's pose covariance (FrameResult::T_w_c_covariance), the keyframe BA not");
  t.choice("covariance", &b.covariance,
           {{"given_points", optimization::BaOptions::Covariance::kGivenPoints},
            {"with_points", optimization::BaOptions::Covariance::kWithPoints}},
           "what the frame's pose covariance describes: given_points, the frame's own measurements with the map as "
           "it is (what differs between consecutive frames: the odometry's step covariance is made from it); "
           "with_points, the pose in the map, the points' uncertainty included");
  t.key("tolerance", &b.tolerance, "converged when an accepted sweep changes the cost by less than this (relative)");
  t.key("threads", &b.threads, "threads for the loops over points (1 = serial)");
  t.key("use_schur", &b.use_schur, "eliminate the points inside each camera update (Schur complement)");
  t.choice("camera_solver", &b.camera_solver,
           {{"conjugate_gradient", Solver::kConjugateGradient}, {"gauss_seidel", Solver::kGaussSeidel}},
           "solver of the reduced camera system: conjugate_gradient (block-Jacobi PCG) or gauss_seidel (block)");
  t.key("camera_iterations", &b.camera_iterations, "iterations (CG) or passes (Gauss-Seidel) of that solver at most");
  t.key("camera_gs_tolerance", &b.camera_gs_tolerance, "its stopping tolerance, relative (both solvers)");
  t.key("plain_gs_passes", &b.plain_gs_passes, "without use_schur: passes of the plain Gauss-Seidel (Eq. 11/12)");
  t.key("initial_lambda", &b.initial_lambda,
        "Levenberg-Marquardt damping at the start, relative to the block diagonals");
  t.key("max_retries", &b.max_retries, "damped re-solves per sweep before giving up");
  t.key("point_iterations", &b.point_iterations,
        "Gauss-Newton steps on every point alone (cameras fixed) after each accepted sweep");
  t.key("point_extrapolation", &b.point_extrapolation,
        "per point, doublings of an accepted step while its cost keeps decreasing (0 = plain Gauss-Newton)");
  t.key("point_tolerance", &b.point_tolerance,
        "a point stops iterating when a step gains less than this share of its cost");

  // --- map ---
  t.section("map");
  auto& m = c.map;
  t.key("max_keyframes", &m.max_keyframes, "keyframes in the active window (>= 2)");
  t.key("keep_newest_keyframes", &m.keep_newest_keyframes,
        "a full window retires the keyframe whose removal costs the current points least parallax, never one of "
        "the newest this many (>= 1)");
  t.key("retire_least_parallax", &m.retire_least_parallax,
        "true: a full window retires the keyframe whose removal costs the current points least parallax; "
        "false: the oldest");
  t.key("retire_fewest_reliant", &m.retire_fewest_reliant,
        "experimental, with retire_least_parallax: the keyframe fewest current points rely on leaves (without it "
        "their widest angle would be under half), not the one whose removal costs least angle");
  t.key("retire_oldest_unless_anchor", &m.retire_oldest_unless_anchor,
        "experimental, with retire_least_parallax: the oldest keyframe leaves unless the current points it "
        "anchors (it is an end of their widest pair) would lose more than anchor_loss_share of their summed "
        "angle without it; then the cheapest leaves");
  t.key("anchor_loss_share", &m.anchor_loss_share,
        "experimental, for retire_oldest_unless_anchor: the share of the angle, in [0, 1]");
  t.key("retire_oldest_beyond_frames", &m.retire_oldest_beyond_frames,
        "experimental, with retire_least_parallax: the oldest keyframe leaves whenever the window spans more "
        "than this many frames (0: never)");
  t.key("archive_voxel_m", &m.archive_voxel_m,
        "retired points archived: 0 = all, else one per voxel of this size (map units)");
  t.key("max_archive_points", &m.max_archive_points,
        "cap on archived points (~70 B each): reaching it doubles the voxel and thins the archive to half");
  t.key("min_observations_to_archive", &m.min_observations_to_archive,
        "retired points with fewer keyframe observations are dropped, not archived");
  t.key("max_dormant_landmarks", &m.max_dormant_landmarks,
        "retired points kept for map reuse (~60 B each), oldest dropped first; 0 = none");

  // --- pipeline ---
  t.section("pipeline");
  t.key("min_init_track_budget_fraction", &c.min_init_track_budget_fraction,
        "tracks shared with the reference frame needed to try initializing, as a share of tracker.max_points, [0, 1]");
  t.internal("min_init_tracks", &c.min_init_tracks,
             "pipeline.min_init_track_budget_fraction x tracker.max_points, at least 8");
  t.key("init_min_disparity_px", &c.init_min_disparity_px,
        "median track displacement before the two-view fit is tried [px]");
  t.key("init_max_pending_frames", &c.init_max_pending_frames,
        "frames kept since the reference; beyond it the reference moves on");
  t.key("min_pose_inliers", &c.min_pose_inliers, "fewer P3P inliers than this: the frame is lost");
  t.key("min_pose_inlier_ratio", &c.min_pose_inlier_ratio,
        "... or fewer than this share of the tracked map points: the pose is not trusted, the frame is lost");
  t.key("weak_pose_max_step_ratio", &c.weak_pose_max_step_ratio,
        "... unless its translation step is within this factor of the motion model's (1: never)");
  t.key("weak_pose_min_survival_ratio", &c.weak_pose_min_survival_ratio,
        "... and this frame kept at least this share of the usual share (median of the last 10 tracked frames) of "
        "the last frame's map tracks: fewer is a cut, whose survivors agree on any prediction (0: always)");
  t.key("keyframe_on_weak_pose", &c.keyframe_on_weak_pose,
        "experimental; false: a frame whose weak pose was kept (weak_pose_max_step_ratio) makes no keyframe, "
        "so no points are triangulated from it");
  t.key("max_outlier_count", &c.max_outlier_count, "times a point may be an outlier before it is removed");
  t.key("max_reprojection_px", &c.max_reprojection_px,
        "an observation's residual after BA above which its point is flagged [px]");
  t.key("ba_fixed_keyframes", &c.ba_fixed_keyframes,
        "oldest keyframes held fixed in the keyframe BA (gauge and scale)");
  t.key("ba_keyframe_sweeps", &c.ba_keyframe_sweeps, "subspace Gauss-Newton sweeps when a keyframe is inserted");
  t.key("ba_frame_sweeps", &c.ba_frame_sweeps, "subspace Gauss-Newton sweeps of the per-frame BA");
  t.key("ba_free_keyframes", &c.ba_free_keyframes, "newest keyframes optimized by the keyframe BA, with their points");
  t.key("defer_keyframe_ba", &c.defer_keyframe_ba,
        "true: in --pipelined mode and live, a keyframe that reaches the mapper while the next frame already "
        "waits leaves its window BA to the next keyframe (never two in a row, never with ba_free_keyframes 1); "
        "sequential runs never defer");
  t.key("ba_free_min_shared", &c.ba_free_min_shared,
        "experimental, 0 = off; > 0: the keyframe BA frees instead every keyframe that sees at least this "
        "share of the newest keyframe's map points (never the gauge), [0, 1]; lost KITTI 02's scale from "
        "one start at every share tried (docs/ROBUSTNESS.md)");
  t.key("keyframe_parallax_px", &c.keyframe_parallax_px,
        "rotation-compensated median parallax to the last keyframe that makes a keyframe [px]");
  t.key("keyframe_min_mapped_ratio", &c.keyframe_min_mapped_ratio,
        "fewer mapped tracks than this share also asks for a keyframe, [0, 1]");
  t.key("max_step_depth_ratio", &c.max_step_depth_ratio,
        "a per-frame step longer than this x the scene depth is a failure");
  t.key("reuse_radius_px", &c.reuse_radius_px,
        "map reuse: a new track this close to the projection of an old point takes it over [px]; 0 = off");
  t.key("reuse_occlusion_ratio", &c.reuse_occlusion_ratio,
        "an old point farther than this x the mapped depth around it is hidden, not reused");
  t.key("reuse_fix_revived", &c.reuse_fix_revived,
        "revived dormant points stay fixed in BA (they anchor the older map)");
  t.key("reuse_dormant_per_frame", &c.reuse_dormant_per_frame,
        "dormant points checked per frame, round robin (bounds the cost)");

  // --- relocalization ---
  t.section("relocalization");
  auto& r = c.relocalization;
  t.key("enabled", &r.enabled, "false: a loss re-initializes at once (a new map)");
  t.key("max_frames", &r.max_frames, "frames with features, lost and not relocalized, before re-initializing");
  t.key("max_keyframes", &r.max_keyframes, "keyframes indexed; the oldest are dropped");
  t.key("max_shared_points", &r.max_shared_points,
        "a keyframe that still sees more than this share of the newest indexed keyframe's points is not indexed "
        "(a near copy), [0, 1]; 1: every keyframe");
  t.key("points_per_keyframe", &r.points_per_keyframe, "described map points kept per keyframe, spread over the image");
  t.key("query_points", &r.query_points, "tracks of a lost frame described, spread over the image");
  t.key("candidates", &r.candidates,
        "best-voted keyframes (and orientations) tried per lost frame, besides the newest");
  t.key("patch_size", &r.patch_size, "BRIEF window at full resolution [px], odd >= 7");
  t.key("smoothing_sigma", &r.smoothing_sigma, "Gaussian smoothing before the BRIEF tests [px]");
  t.key("max_distance", &r.max_distance, "accepted Hamming distance (of 256)");
  t.key("ratio", &r.ratio, "best / second-best distance, (0, 1]");
  t.key("min_inliers", &r.min_inliers, "P3P inliers needed to accept a pose (>= 6)");
  t.key("min_inlier_ratio", &r.min_inlier_ratio, "P3P inliers / descriptor matches needed, (0, 1]");
  t.key("upside_down", &r.upside_down, "also look for the frame turned by 180 degrees (a rolled camera)");

  // --- ground ---
  t.section("ground");
  auto& g = c.ground;
  t.key("enabled", &g.enabled,
        "ground vehicle: hold the camera's height above the road plane constant (the map's scale); off for drones "
        "and hand-held cameras");
  t.key("max_step_height_ratio", &g.max_step_height_ratio,
        "no measurement when the camera moved more than this x its height in the last frame (> 0): at speed the "
        "road's near points are lost and the far ones bias the plane");
  t.key("reference_keyframes", &g.reference_keyframes,
        "the first this many consecutive keyframes with a road plane whose heights agree (within max_change of "
        "their median) set the height kept (their median, >= 1)");
  t.key("window", &g.window, "the map's current height is the median of this many last measurements (>= 1)");
  t.key("tolerance", &g.tolerance,
        "a scale error (reference / current height - 1) within this share is noise: no correction, [0, 1)");
  t.key("spread_factor", &g.spread_factor,
        "the tolerance grows by this x the spread of the window's heights (median relative deviation from "
        "their median): disagreeing measurements must be further off to correct (>= 0; 0: fixed tolerance)");
  t.key("gain", &g.gain, "share of the scale error beyond the tolerance corrected at each keyframe, (0, 1]");
  t.key("max_change", &g.max_change,
        "a plane whose height is off the map's current one by more than this share is not taken for the road, "
        "unless `window` consecutive ones agree among themselves (the map's scale moved), (0, 1)");
  t.key("max_tilt_deg", &g.plane.max_tilt_deg,
        "largest angle between the road's normal and the camera's down (y) axis [deg], (0, 90)");
  t.key("min_depression_deg", &g.plane.min_depression_deg,
        "road candidates: map points at least this angle below the optical axis [deg], [0, 90)");
  t.key("inlier_ratio", &g.plane.inlier_ratio, "a road point is within this x the camera height of the plane, (0, 1)");
  t.key("min_inlier_budget_fraction", &g.min_inlier_budget_fraction,
        "fewer road points than this share of tracker.max_points: no measurement at this keyframe, [0, 1]");
  t.internal("min_inliers", &g.plane.min_inliers, "ground.min_inlier_budget_fraction x tracker.max_points, at least 3");
  t.key("min_inlier_fraction", &g.plane.min_inlier_fraction,
        "fewer road points than this share of the candidates: no measurement, [0, 1]");
  t.key("iterations", &g.plane.iterations, "RANSAC samples of the plane fit (>= 1)");

  // --- dense ---
  t.section("dense");
  auto& d = c.dense;
  auto& tsdf = d.integrator.tsdf;
  t.key("enabled", &c.dense_enabled, "run the dense reconstruction (vitamin_e_run writes mesh.ply)");
  t.key("denoise", &d.denoise, "NLTGV2-L1 smoothing of each frame mesh before fusion");
  t.key("min_points", &d.min_points, "frames with fewer triangulated points are not meshed (>= 3)");
  t.key("nice_increment", &d.nice_increment,
        "the meshing and fusion threads run this many nice levels below the SLAM's (Linux), [0, 19]: they take the "
        "time the SLAM's threads leave on the cores; 0: the same priority");
  t.shared("min_depth", std::vector<double*>{&d.mesher.min_depth, &d.prune.min_depth, &tsdf.min_depth},
           "nearer points are not meshed and nearer depths not fused (map units)");
  t.shared("max_depth", std::vector<double*>{&d.mesher.max_depth, &d.prune.max_depth, &tsdf.max_depth},
           "farther points are not meshed and farther depths not fused (map units)");
  t.key("mesh_max_edge_px", &d.mesher.max_edge_px,
        "building a frame mesh: triangles with a longer edge are dropped [px]");
  t.key("mesh_max_normal_angle_deg", &d.mesher.max_normal_angle_deg,
        "building: triangles seen more obliquely than this are dropped [deg]");
  t.key("mesh_max_inv_depth_jump", &d.mesher.max_inv_depth_jump,
        "building: triangles whose (max - min) / max inverse depth exceeds this are dropped");
  t.key("mesh_drop_unused_vertices", &d.mesher.drop_unused_vertices, "building: vertices in no triangle are removed");
  t.internal("mesh_jump_on_measured", &d.mesher.jump_on_measured,
             "no effect when a mesh is built (its measured and smoothed depths are still the same)");
  t.key("max_edge_px", &d.prune.max_edge_px,
        "pruning after the smoothing: triangles with a longer edge are dropped [px]");
  t.key("max_normal_angle_deg", &d.prune.max_normal_angle_deg,
        "pruning: triangles seen more obliquely than this are dropped [deg]");
  t.key("max_inv_depth_jump", &d.prune.max_inv_depth_jump,
        "pruning: triangles whose (max - min) / max inverse depth exceeds this are dropped");
  t.key("prune_jump_on_measured", &d.prune.jump_on_measured,
        "pruning applies that jump test to the measured depths too (smoothing must not bridge a real jump)");
  t.key("prune_drop_unused_vertices", &d.prune.drop_unused_vertices, "pruning: vertices in no triangle are removed");
  t.key("nltgv_alpha", &d.nltgv.alpha, "NLTGV2: weight of the first-order (affine) term");
  t.key("nltgv_beta", &d.nltgv.beta, "weight of the gradient smoothness term (normalized-coordinate units)");
  t.key("nltgv_lambda", &d.nltgv.lambda, "weight of the L1 data term");
  t.key("nltgv_iterations", &d.nltgv.iterations, "primal-dual iterations (cold start)");
  t.key("nltgv_warm_iterations", &d.nltgv.warm_iterations, "iterations when most vertices were warm-started");
  t.key("nltgv_theta", &d.nltgv.theta, "over-relaxation, [0, 1]");
  t.key("nltgv_support_sigma", &d.nltgv.support_sigma,
        "relative inverse-depth jump scale of the support weights (0: all weights 1)");
  t.key("nltgv_min_support", &d.nltgv.min_support, "floor of the support weights, (0, 1]");
  t.key("nltgv_warm_start", &d.nltgv.warm_start, "keep the solution by track id for the next frame");
  t.key("nltgv_warm_start_primal", &d.nltgv.warm_start_primal,
        "also start from the previous inverse depths and gradients (else only the duals)");
  t.key("voxel_size", &tsdf.voxel_size, "TSDF voxel size (map units)");
  t.key("truncation", &tsdf.truncation, "band half-width around the surface (map units, >= voxel_size)");
  t.key("max_weight", &tsdf.max_weight, "cap of a voxel's running weight");
  t.key("block_voxels", &tsdf.block_voxels, "voxels per block side, [2, 64]");
  t.key("min_extract_weight", &tsdf.min_extract_weight, "voxels lighter than this count as unobserved in the mesh");
  t.key("weight_depth_ref", &tsdf.weight_depth_ref,
        "a measurement weighs min(1, (this / z)^2) (map units); 0: every measurement weighs 1");
  t.key("raster_downscale", &tsdf.raster_downscale,
        "frame meshes are rasterized at (width, height) / this, [0, 16]; 0: half a voxel's size in pixels at the "
        "mesh's far depth (at most 8)");
  t.key("asynchronous", &d.integrator.asynchronous, "fuse on the integrator's own thread");
  t.key("queue_capacity", &d.integrator.queue_capacity, "frames queued for that thread (>= 1)");
  t.key("block_when_full", &d.integrator.block_when_full,
        "a full queue blocks the caller (true: every frame is fused) or drops the oldest frame (false)");
  return std::move(t.fields);
}

const std::vector<SectionInfo>& configSections() {
  // In the order of the table (and of describe() and docs/CONFIG.md).
  static const std::vector<SectionInfo> sections = {
      {"tracker",
       "Dense curvature-extrema tracking: `tracking::TrackerConfig` (include/vitamin_e/tracking/dense_tracker.h)."},
      {"init", "Two-view initialization: `geometry::TwoViewConfig` (include/vitamin_e/geometry/two_view.h)."},
      {"pnp", "Camera pose from P3P + RANSAC, refined with Geman-McClure: `geometry::PnpConfig` "
              "(include/vitamin_e/geometry/pnp.h)."},
      {"triangulation",
       "New map points: `geometry::TriangulationConfig` (include/vitamin_e/geometry/triangulation.h)."},
      {"ba", "Subspace Gauss-Newton bundle adjustment: `optimization::BaOptions` "
             "(include/vitamin_e/optimization/subspace_gn.h)."},
      {"map", "Keyframe window, point archive and dormant points: `map::MapConfig` (include/vitamin_e/map/map.h)."},
      {"pipeline", "The SLAM system's own parameters: `pipeline::SystemConfig` "
                   "(include/vitamin_e/pipeline/system_config_types.h)."},
      {"relocalization", "Finding a lost camera again in the map: `pipeline::RelocalizerConfig` "
                         "(include/vitamin_e/pipeline/relocalizer.h)."},
      {"ground", "Scale from the road, for a camera on a ground vehicle (off by default): at each keyframe the "
                 "road plane under the camera measures the camera's height, and the map is scaled to keep it: "
                 "`pipeline::GroundScaleConfig` (include/vitamin_e/pipeline/ground_scale.h), the plane fit "
                 "`geometry::GroundPlaneConfig` (include/vitamin_e/geometry/ground_plane.h)."},
      {"dense", "Dense reconstruction in map units (the map unit is the median scene depth at initialization): "
                "frame mesh, NLTGV2-L1 smoothing, pruning, TSDF fusion: `fusion::DenseMapperConfig` "
                "(include/vitamin_e/fusion/dense_mapper.h). Run on the SLAM's per-frame points by vitamin_e_run and "
                "by the ROS meshing nodelet (its `~config_file`), with the same meaning; not by pipeline::System."},
  };
  return sections;
}

}  // namespace vitamin_e::pipeline::detail
