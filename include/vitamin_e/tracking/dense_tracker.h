#pragma once
// Dense curvature-extrema tracking front end (VITAMIN-E, CVPR 2019, section 2).
//
// Per frame: (1) curvature image kappa = fy^2 fxx - 2 fx fy fxy + fx^2 fyy of a
// lightly smoothed float image; (2) dominant flow y = A x + b from BRIEF matches
// on the image shrunk to `brief_scale`, fitted by IRLS with the Geman-McClure
// kernel; (3) every live point is predicted with the flow and moved by hill
// climbing F = s*kappa(x) + lambda * w(|x - x_bar|) (s = the point's curvature
// sign, w = 1 - rho) to a local maximum, refined to sub-pixel precision and
// checked forward-backward on the previous curvature image; the reported
// position is filtered with a patch alignment of the pre-smoothed images (see
// extremum_weight), which must also confirm the climbed extremum (see
// max_align_disagreement_px); (4) new extrema are
// spawned in grid cells that lost their points. Curvature is normalized by a
// robust per-frame scale (median |kappa|) so that lambda and the thresholds mean
// the same under exposure changes. That median follows an exposure step only in
// part (flat, noisy areas dominate it; the peaks scale by ~gain^3), so the
// strength-change test compares each track with the frame's median change
// (relative_strength_change), the absolute floor of tracked points follows the
// change (floor_follows_exposure) and the patch alignment fits a contrast gain
// on such frames (align_gain).
#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

namespace vitamin_e::tracking {

struct TrackerConfig {
  // --- detection ---
  int max_points = 8000;         // upper bound on live points per frame (> 0)
  int grid_cell_px = 8;          // bucketing cell size [px]; new points go to under-filled cells
  int max_per_cell = 2;          // live points allowed per cell (>= 1)
  int nms_radius_px = 1;         // an extremum must dominate its (2r+1)^2 window, same sign (>= 1)
  int border_px = 8;             // no point closer than this to the image border (>= 2)
  double smoothing_sigma = 2.0;  // Gaussian pre-smoothing before derivatives [px] (0 = none)
  bool adaptive_smoothing =
      true;  // raise the smoothing on noisy images (noise / median gradient above noise_reference)
  double max_smoothing_sigma = 3.0;  // upper bound of the adaptive smoothing [px] (>= smoothing_sigma)
  double noise_reference =
      0.5;  // noise sigma / median |raw gradient| above which smoothing grows as sqrt(ratio/ref) (> 0)
  double kappa_smoothing_sigma = 0.0;  // Gaussian smoothing of kappa itself before extrema/tracking [px] (0 = none)
  double min_curvature = 1.0;          // detection threshold on |kappa| / median|kappa| (>= 0)
  double min_abs_curvature = 0.5;      // absolute floor on |kappa| [DN^3/px^4]; flat/black images give nothing
  // --- dominant flow (BRIEF on a shrunk image + Geman-McClure affine fit) ---
  double brief_scale = 1.0 / 6.0;     // shrink factor of the matching image, (0, 1]
  int brief_max_keypoints = 400;      // strongest curvature extrema of the small image described
  int brief_patch_size = 15;          // side of the BRIEF test window in the small image [px], odd >= 7
  int brief_max_distance = 70;        // max Hamming distance of an accepted match (of 256)
  double brief_ratio = 0.9;           // best/second-best distance ratio test, (0, 1]; matches are also cross-checked
  double flow_sigma_px = 3.0;         // final Geman-McClure sigma of the affine fit [full-res px] (> 0)
  double flow_sigma_start_px = 30.0;  // annealing starts here and halves down to flow_sigma_px (>= flow_sigma_px)
  int flow_iterations = 5;            // IRLS iterations per annealing level (>= 1)
  int flow_min_matches = 8;           // fewer inliers than this: flow_ok = false, identity + previous b used
  // --- extrema tracking ---
  double lambda = 8.0;          // weight of the prediction prior in F, in normalized-curvature units (>= 0)
  double track_sigma_px = 1.5;  // Geman-McClure sigma of w(|x - x_bar|) [px] (> 0)
  int max_climb_steps = 12;     // hill-climbing steps (8-neighbour moves) before giving up (>= 1)
  // [0, 1): move the sub-pixel extremum this far toward x_bar when within 1 px (temporal filter; 0 = pure
  // extremum); replaced by the patch filter (extremum_weight < 1) where the patch alignment succeeds
  double prediction_blend = 0.3;
  // after maximizing F, climb kappa alone (no prior) up to this many steps; 0 = off (the prior helps on noisy images)
  int polish_steps = 0;
  double fb_threshold_px = 1.0;      // forward-backward check: max distance back to the old position [px] (> 0)
  double min_track_curvature = 0.5;  // a tracked point dies when s*kappa/median|kappa| falls below this (>= 0)
  double max_curvature_ratio = 1.5;  // ... or when its normalized |kappa| changes by more than this factor (>= 1)
  // ... relative to the frame's median change over all climbed tracks (an exposure step scales every peak by
  // about the brightness ratio cubed, which the noise-dominated median |kappa| does not follow); false: relative to 1
  bool relative_strength_change = true;
  double strength_ratio_min_change = 0.1;  // ... when that median change leaves [1/(1+this), 1+this]; within, against 1
                                           // (ordinary frames scatter by a few %) (>= 0)
  // for a tracked point, min_abs_curvature follows the frames' common raw curvature change since the point was
  // detected (exposure steps, smoothing changes), down to 1/16 of it: a darkening does not end the tracks that the
  // relative tests keep; new points always need the full floor (false: fixed floor)
  bool floor_follows_exposure = true;
  double min_track_sharpness = 0.05;      // ... or when the peak it climbed to has peakSharpness() below this [1/px^2]:
                                          // a ridge or plateau of kappa lets the position slide (0 = off)
  bool strength_at_subpixel_peak = true;  // the weak / strength-change checks use the height of the fitted
                                          // sub-pixel peak (true) or kappa at the integer maximum (false)
  double extremum_weight = 0.3;           // (0, 1]: reported position = x_p + w * (extremum - x_p), x_p = the previous
                                          // position carried over by patch alignment on the smoothed images (a
                                          // complementary filter: the extremum anchors against drift, the patch
                                          // removes its frame-to-frame jitter); 1 = the extremum alone (off)
  int align_radius_px = 4;                // patch of that alignment: (2r+1)^2 px, r in [1, 4]
  int align_iterations = 2;               // its Gauss-Newton steps (>= 1)
  // that alignment fits a contrast gain per patch as well as the mean on frames whose contrast changed (an
  // exposure step scales the patch; false: mean only)
  bool align_gain = true;
  double align_gain_min_change = 0.03;  // ... by more than this fraction, estimated as the cube root of the median
                                        // peak ratio (kappa is cubic in intensity); 0 = on every frame (>= 0)
  // confirmation: a track dies when that patch alignment (started from the flow prediction, independent of the
  // climb) fails or ends farther than this from the climbed extremum [px]: the climb jumped to a neighbouring
  // extremum (0 = off; needs extremum_weight < 1)
  double max_align_disagreement_px = 1.0;
  double confirm_max_unaligned_fraction = 1.0;  // [0, 1]: that check is skipped on a frame where the patch
                                                // alignment fails for more than this fraction of the tracks (1 = never)
  bool refine_flow = true;       // refit A, b to the tracked points (GM, down to 1 px) and track again from it
  bool predict_parallax = true;  // add each point's last residual to the dominant flow (x_bar = A x + b + r)
  // a track the flow's prediction lost is tracked once more from its prior (track()'s priors: where the caller's
  // map and motion model put it), when the prior, corrected by the BRIEF matches around the map tracks, lies
  // outside the flow's inlier band (2.5 flow_sigma_px) of that prediction: a second layer that one affine flow
  // cannot follow (docs/PERFORMANCE.md, "Tracks found again from the map")
  bool retry_from_prior = true;
  // a track retried from its prior passes the strength-change check within a band widened by the prior's size
  // change (TrackPrior::scale, either way, at most 4x): a point the camera nears or leaves by a large step changes
  // its curvature peak with its size; a map track the check ended on a frame whose prior changes its size by more
  // than 5 % is retried (docs/PERFORMANCE.md, "Dropped frames")
  bool strength_follows_prior_scale = true;
  // --- execution ---
  int threads = 2;  // stripes run in parallel (cv::parallel_for_); 1 = serial (>= 1)

  // Throws std::invalid_argument naming the first bad field.
  void validate() const;
};

// Where the caller expects a track in the next frame (e.g. its map point seen
// from the motion model's pose), in input image pixels.
struct TrackPrior {
  std::uint64_t id = 0;
  Eigen::Vector2f uv = Eigen::Vector2f::Zero();
  float scale = 1.f;  // its image size here over its size in the last frame (depth there / depth here); 1: unknown
};

struct TrackedPoint {
  std::uint64_t id = 0;                          // stable while the point is tracked
  Eigen::Vector2f uv = Eigen::Vector2f::Zero();  // sub-pixel position in the input (distorted) image
  int age = 0;                                   // frames tracked before this one (0 = detected in this frame)
  float curvature = 0.f;                         // normalized kappa at uv (sign tells min/max)
  std::uint8_t intensity = 0;                    // input image intensity at the nearest pixel
};

struct TrackerFrame {
  double timestamp = 0;
  std::vector<TrackedPoint> points;                 // all live points of this frame (tracked first, then new)
  Eigen::Matrix2d A = Eigen::Matrix2d::Identity();  // dominant flow prev -> cur: y = A x + b
  Eigen::Vector2d b = Eigen::Vector2d::Zero();
  bool flow_ok = false;  // the affine fit had >= flow_min_matches inliers
  int flow_matches = 0;  // BRIEF matches used by the fit (after cross-check/ratio)
  int num_tracked = 0, num_new = 0, num_lost = 0;
  int num_from_prior = 0;  // of num_tracked: found from their prior after the flow's prediction lost them
  // num_lost by the check that ended the track: "climb" (no local maximum of F
  // near the prediction), "weak" (below min_track_curvature), "strength_change"
  // (max_curvature_ratio), "flat" (min_track_sharpness), "back_climb" and
  // "forward_backward" (the backward climb), "unconfirmed" (max_align_disagreement_px),
  // "duplicate" (two tracks on a pixel).
  std::map<std::string, int> lost_by;
  std::map<std::string, int> lost_new_by;  // the part of lost_by that was detected in the previous frame
  // Every ended track: its id and the lost_by name of the check that ended it
  // (a static string), so that the losses of mapped tracks can be told apart
  // from the churn of young ones.
  std::vector<std::pair<std::uint64_t, const char*>> ended;
  double noise_ratio = 0;                   // estimated image noise sigma / median |gradient| of this frame
  double smoothing_sigma = 0;               // pre-smoothing used for this frame [px]
  double curvature_scale = 0;               // median |kappa| of this frame (the unit of the normalized curvature)
  double strength_ratio = 1;                // median over the climbed tracks of new / old normalized strength (1 when
                                            // relative_strength_change is off or too few tracks)
  double patch_gain = 1;                    // median contrast gain of the patch alignment (1 where no gain was fitted)
  std::map<std::string, double> timing_ms;  // "curvature", "flow", "track", "detect", "total"
};

class DenseTracker {
 public:
  explicit DenseTracker(const TrackerConfig& config = {});  // validates config
  ~DenseTracker();
  DenseTracker(DenseTracker&&) noexcept;
  DenseTracker& operator=(DenseTracker&&) noexcept;

  // CV_8UC1 image of any size (>= 2*border_px+3 on each side); throws
  // std::invalid_argument on other types or an empty image. An image whose size
  // differs from the previous one restarts tracking (all points new).
  // priors: expected positions of some tracks in this frame, sorted by id (see retry_from_prior).
  TrackerFrame track(const cv::Mat& gray, double timestamp, const std::vector<TrackPrior>& priors = {});
  // The same, with the priors asked for only when they are used: after the dominant flow has
  // tracked every track (only with retry_from_prior). A pipelined caller waits there for the
  // mapping of the frame before, so that they come from the newest map and pose.
  using PriorProvider = std::function<std::vector<TrackPrior>()>;
  TrackerFrame track(const cv::Mat& gray, double timestamp, const PriorProvider& priors);
  // The back end removes outlier tracks: they are not tracked further and their
  // cells are refilled with new points on the next frame. Unknown ids are ignored.
  // Returns the number of tracks removed.
  std::size_t dropTracks(const std::vector<std::uint64_t>& ids);
  // Forgets all points and the previous frame; ids keep increasing.
  void reset();
  // New tracks get ids >= first_id from now on (ids never decrease): tracks
  // must not take the ids of the points of a map loaded from a file.
  void reserveIdsBelow(std::uint64_t first_id);
  const TrackerConfig& config() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace vitamin_e::tracking
