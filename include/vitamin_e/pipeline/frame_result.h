#pragma once
// What the SLAM system returns for every input frame. Plain data, no ROS: the
// ROS layer and the offline runner turn it into messages and files.
#include <Eigen/Geometry>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace vitamin_e::pipeline {

enum class TrackingState {
  kInitializing,  // waiting for enough parallax to build the first map
  kTracking,      // pose estimated for this frame
  kLost,          // tracking failed at this frame; the system relocalizes (or re-initializes)
  kRelocalizing,  // lost: looking for the camera in the existing map (no pose this frame)
};

// Why a frame is in its state: the transition that led there (pipeline::Recovery).
enum class StateReason {
  kWaitingForMap,           // initializing: no map yet (FrameResult::message says what is missing)
  kInitialized,             // tracking: a map was built at this frame
  kTracked,                 // tracking: pose from the map
  kPoseFailed,              // lost: no pose from the tracked map points
  kPoseJumped,              // lost: the pose moved far beyond the scene depth
  kRelocalized,             // tracking: found again in the map (at the loss frame or later)
  kNotRelocalized,          // relocalizing: not found in the map at this frame
  kRelocalizationTimedOut,  // lost: not found in relocalization.max_frames frames: a new map follows
  kSkipped,                 // not processed: the stamp did not increase (the state is the system's)
};

// A relocalizing frame's search (FrameDiagnostics::relocalization).
enum class RelocalizationOutcome {
  kNotTried,     // the frame was not relocalizing
  kRelocalized,  // found, and confirmed by the map points around the pose
  kNotFound,     // no pose from the keyframe index
  kDidNotHold,   // a pose found, not confirmed by the map points around it
};

// Lower-case names ("tracking", "pose_failed", "not_found"; "" for kNotTried):
// the words of logs, stats.json and the ROS status.
const char* toString(TrackingState state);
const char* toString(StateReason reason);
const char* toString(RelocalizationOutcome outcome);

// One densely tracked point of the current frame.
struct FramePoint {
  std::uint64_t track_id = 0;                     // stable over the frames the point is tracked
  Eigen::Vector2f uv;                             // pixel in the (distorted) input image
  bool has_position = false;                      // true once triangulated
  Eigen::Vector3d p_w = Eigen::Vector3d::Zero();  // map position (world frame)
  std::uint8_t intensity = 0;                     // image intensity at uv
};

// Per-frame counters of the map's life: where tracks come from, why
// they end, how many still carry a map point, how the pose was found and why
// new points are (not) made. Filled by System from the values its stages
// return; printed by vitamin_e_run --log-frames and summarized in stats.json.
struct FrameDiagnostics {
  // front end (this frame's tracking step)
  // The balance: tracks of the previous frame = (this frame's tracks - born) + lost + dropped.
  int tracks_born = 0;                 // new tracks detected
  int tracks_lost = 0;                 // tracks of the previous frame the tracker ended
  int tracks_dropped = 0;              // tracks of the previous frame the back end ended (outliers)
  int tracks_from_prior = 0;           // of the tracked ones: found from the map's prior after the flow lost them
  std::map<std::string, int> lost_by;  // tracks_lost by the tracker's check (tracking::TrackerFrame::lost_by)
  // the map points the previous frame's tracks carried (when it was tracked)
  std::size_t prev_map_points = 0;
  std::size_t prev_map_tracked = 0;             // of them still tracked in this frame
  std::size_t prev_map_left_view = 0;           // of the ended ones: project outside the image at this frame's pose
  std::size_t prev_map_lost_in_view = 0;        // ... project inside it: the tracker lost them in view
  std::map<std::string, int> prev_map_lost_by;  // the ended ones by the tracker's check ("dropped": ended by
                                                // the back end, not by the tracker)
  // pose
  int pose_points = 0;   // map points given to P3P + RANSAC
  int pose_inliers = 0;  // its inliers (0: not run)
  int reused = 0;        // map points taken over by new tracks (map reuse)
  // initialization (the frame that built a map): its motion came from the homography (a planar
  // scene), and another motion explained the two views as well (the map may be built on the wrong one)
  bool init_from_homography = false;
  bool init_ambiguous = false;
  // mapping
  bool keyframe = false;              // a keyframe was inserted (the first map's frame counts)
  bool window_ba_deferred = false;    // its window BA was left to the next keyframe (the mapper was behind)
  double keyframe_parallax_px = 0.0;  // rotation-compensated median parallax to the last keyframe [px]
  std::size_t keyframes = 0;          // keyframes in the window after this frame
  int triangulated = 0;               // new map points made this frame
  std::map<std::string, int> triangulation_rejected_by;  // tried but refused: "parallax", "reprojection",
                                                         // "cheirality", "other"
  // The candidates: unmapped tracks seen by a keyframe older than this frame
  // (since the track was detected), waiting for the parallax that triangulates them.
  std::size_t candidates = 0;
  std::size_t candidates_two_keyframes = 0;  // of them seen by two or more keyframes (tried at each keyframe)
  double candidate_parallax_deg = 0.0;       // median angle between a candidate's ray in the first keyframe after
                                             // its detection and its ray in this frame (world frame): its parallax now
  // relocalization (a frame that looked for the camera in the map)
  RelocalizationOutcome relocalization = RelocalizationOutcome::kNotTried;
  int relocalization_matches = 0;  // descriptor matches with the best keyframe
  int relocalization_inliers = 0;  // P3P inliers among them
  // ground scale (ground.enabled, at keyframes): the camera's height above the road plane
  // (map units, before this frame's correction; 0: no plane found), its road points, and the
  // factor the map was scaled by about the camera (1: unchanged)
  double ground_height = 0.0;
  int ground_inliers = 0;
  double scale_correction = 1.0;

  // prev_map_tracked / prev_map_points (1 when there were none)
  double prevMapTrackedFraction() const {
    return prev_map_points ? static_cast<double>(prev_map_tracked) / static_cast<double>(prev_map_points) : 1.0;
  }
};

struct FrameResult {
  std::uint64_t frame_index = 0;  // 0-based index of the frame in the stream
  double timestamp = 0.0;         // seconds, as given to process()
  TrackingState state = TrackingState::kInitializing;
  StateReason reason = StateReason::kWaitingForMap;         // why it is in that state
  bool pose_valid = false;                                  // T_w_c is meaningful (state == kTracking)
  Eigen::Isometry3d T_w_c = Eigen::Isometry3d::Identity();  // camera (optical) in world
  // Covariance of T_w_c from the per-frame BA (optimization::BaSummary::camera_covariance, as
  // ba.covariance says: by default the frame's own measurements, the map held as it is): of the
  // right perturbation delta = (rho, phi), T_w_c * expSE3(delta), in the camera frame, map
  // units^2 and rad^2. Meaningful only when the flag is set. The odometry's step covariance is
  // made from it (step_covariance.h).
  Eigen::Matrix<double, 6, 6> T_w_c_covariance = Eigen::Matrix<double, 6, 6>::Zero();
  bool T_w_c_covariance_valid = false;
  std::vector<FramePoint> points;           // tracked points of this frame
  std::size_t num_tracked = 0;              // 2D tracks alive
  std::size_t num_mapped = 0;               // tracks with a 3D position
  std::size_t map_size = 0;                 // points in the map
  int init_retries = 0;                     // re-initializations so far (each one a new map)
  int relocalizations = 0;                  // losses recovered in the existing map so far
  std::map<std::string, double> timing_ms;  // this frame's per-stage times
  std::string message;                      // a human-readable note (why lost, why waiting)
  FrameDiagnostics diagnostics;             // the counters of the map's life this frame
};

// A tracked frame's pose as soon as it is known, before the frame's map work (a keyframe's
// triangulation and window BA, the relocalizer's index): what a live caller publishes at
// once (System::process's PoseListener). The frame's FrameResult follows with the pose the
// map work settled on: the same one, unless the frame became a keyframe (the window BA moves
// it a little) or the ground held the map's scale.
struct FramePose {
  std::uint64_t frame_index = 0;  // as FrameResult::frame_index
  double timestamp = 0.0;
  Eigen::Isometry3d T_w_c = Eigen::Isometry3d::Identity();
  Eigen::Matrix<double, 6, 6> T_w_c_covariance = Eigen::Matrix<double, 6, 6>::Zero();  // as FrameResult's
  bool T_w_c_covariance_valid = false;
  bool keyframe = false;  // the frame becomes a keyframe (FrameDiagnostics::keyframe)
};

// The pose of a result with a valid one (pose_valid), for callers that publish poses from
// results and from early FramePoses alike.
FramePose poseOf(const FrameResult& result);

}  // namespace vitamin_e::pipeline
