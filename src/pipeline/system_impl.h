#pragma once
// pipeline::System's composition (not installed): the stages, each owning its
// own state, and what the frames share across them (the map, the motion model,
// the tracking status, the trajectory). The per-frame data travels in a
// FrameContext from stage to stage.
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <utility>
#include <vector>

#include "vitamin_e/map/map.h"
#include "vitamin_e/pipeline/front_end.h"
#include "vitamin_e/pipeline/ground_scale.h"
#include "vitamin_e/pipeline/initializer.h"
#include "vitamin_e/pipeline/localizer.h"
#include "vitamin_e/pipeline/map_reuse.h"
#include "vitamin_e/pipeline/map_update.h"
#include "vitamin_e/pipeline/mapper.h"
#include "vitamin_e/pipeline/motion_model.h"
#include "vitamin_e/pipeline/recovery.h"
#include "vitamin_e/pipeline/relocalizer.h"
#include "vitamin_e/pipeline/system.h"
#include "vitamin_e/pipeline/track_priors.h"
#include "vitamin_e/pipeline/track_survival.h"

namespace vitamin_e::pipeline {

// Counts over the whole run (the public System getters).
struct RunCounters {
  std::uint64_t frames_processed = 0;
  std::uint64_t frames_tracked = 0;
  long long first_init_frame = -1;          // frame index of the first successful initialization
  std::uint64_t localized_before_init = 0;  // poses recorded for frames before it
  int init_retries = 0;                     // new maps after a loss
  int relocalizations = 0;                  // losses recovered in the existing map
  std::uint64_t reused_map_points = 0;      // map points taken over by new tracks (map reuse)
};

// The tracks the front end ended at this frame, with the check that ended
// them (a static string), sorted by id.
using EndedTracks = std::vector<std::pair<std::uint64_t, const char*>>;

struct System::Impl {
  Impl(const SystemConfig& config, const camera::Camera& camera);

  TrackedFrame trackFrame(const cv::Mat& image, double timestamp, const std::string& timestamp_text,
                          const std::function<void()>& before_priors, std::uint64_t frames_in_mapping);
  FrameResult mapFrame(TrackedFrame&& frame, const PoseListener& on_pose);
  void reset();
  bool restartTracking();

  // The steps of mapFrame (system.cpp), one per tracking state: initialize,
  // track, relocalize; Recovery decides which.
  void initialize(FrameContext& frame, FrameResult* result);
  void startMap(InitialMap* m, const FrameContext& frame);  // the initializer's map becomes the map
  // The first map's frames get their poses; returns the current frame's.
  Eigen::Isometry3d localizeInitialFrames(const InitialMap& m, const FrameContext& frame);
  // on_pose (may be empty) hears the pose before the map work.
  void track(FrameContext& frame, const EndedTracks& ended, const PoseListener& on_pose, FrameResult* result);
  // At an estimated pose: map points reused by new tracks, the per-frame BA; returns the
  // refined pose (its covariance in *result).
  Eigen::Isometry3d refineTrackedPose(const FrameContext& frame, const Eigen::Isometry3d& T_w_c, FrameResult* result);
  PoseEstimate estimatePose(const FrameContext& frame, const EndedTracks& ended, FrameResult* result);
  // At a tracked pose: a keyframe when `decision` says so, the scale held to the road,
  // the scene depth updated. Returns the frame's pose (moved by a keyframe BA).
  Eigen::Isometry3d extendMap(const FrameContext& frame, Eigen::Isometry3d T_w_c, const KeyframeDecision& decision,
                              FrameDiagnostics* d);
  // The frame as a keyframe: triangulation, window BA, relocalizer index.
  // Returns the frame's pose after the window BA.
  // may_defer: the window BA may be left to the next keyframe (the mapper is behind; config.defer_keyframe_ba).
  Eigen::Isometry3d insertKeyframe(const FrameContext& frame, const Eigen::Isometry3d& T_w_c, FrameDiagnostics* d,
                                   bool may_defer = false);
  // A loss (kPoseFailed, kPoseJumped; why: the message's detail).
  void lose(FrameContext& frame, RecoveryEvent event, const std::string& why, FrameResult* result);
  // A frame of the relocalizing state.
  void relocalize(FrameContext& frame, FrameResult* result);
  // The frame looked for in the relocalizer's index and, when found, tracked from there.
  struct MapSearch {
    bool found = false;
    std::string message;  // where it was found, or why not
  };
  MapSearch searchMap(FrameContext& frame, FrameResult* result);
  bool resume(FrameContext& frame, const Eigen::Isometry3d& T_w_guess, FrameResult* result);
  // The frame's event through Recovery: its state and reason set in *result,
  // and a new map started when the transition asks for one.
  Transition report(RecoveryEvent event, const FrameContext& frame, FrameResult* result);
  static void setOutcome(const Transition& t, FrameResult* result);
  // The frame's points, counts and backlog in its result.
  void describeFrame(const FrameContext& frame, FrameResult* result);

  // Changes of the map the stages return, applied (the offenders' tracks end).
  AppliedMapUpdate applyUpdate(const MapUpdate& update);
  void penalize(const std::vector<std::uint64_t>& outliers);
  int reuseMapPoints(const FrameContext& frame, const Eigen::Isometry3d& T_w_c, bool all_dormant);
  FrameRefinement refine(const FrameContext& frame, const Eigen::Isometry3d& T_w_c);  // per-frame BA, applied
  void markTracksSeen(const FrameContext& frame);
  // At a keyframe: the road plane under the camera measures the map's scale
  // (ground.enabled); a correction rescales everything that holds map units.
  void holdGroundScale(const FrameContext& frame, const Eigen::Isometry3d& T_w_c, FrameDiagnostics* d);
  void recordPose(double t, const std::string& text, const Eigen::Isometry3d& T_w_c);
  // The previous frame's map tracks this frame still tracks (d->prev_map_points, prev_map_tracked);
  // returns the ids of the ended ones, sorted.
  std::vector<std::uint64_t> countSurvivingMapTracks(const FrameContext& frame, FrameDiagnostics* d) const;
  // Diagnostics: where the ended map tracks went (by reason, out of view or in view at T_w_c).
  void diagnoseEndedMapTracks(const std::vector<std::uint64_t>& ended_ids, const EndedTracks& ended,
                              const Eigen::Isometry3d& T_w_c, FrameDiagnostics* d) const;
  // A loss is not given up for a new map (system_map_io.cpp).
  bool keepRelocalizing() const;

  SystemConfig config;
  camera::Camera camera;
  // stages
  FrontEnd front_end;
  Initializer initializer;
  Localizer localizer;
  MapReuse reuse;
  Mapper mapper;
  Relocalizer relocalizer;
  GroundScale ground;
  Recovery recovery;  // the tracking state
  // shared across frames (mapping thread only)
  map::Map map;
  MotionModel motion;
  bool initialized_once = false;
  std::uint64_t mapping_sequence = 0;  // this frame's TrackedFrame::sequence (tags its drops)
  bool mapper_behind = false;          // this frame's TrackedFrame::mapper_behind
  bool priors_awaited = false;         // this frame's TrackedFrame::priors_awaited
  bool window_ba_deferred = false;     // the last keyframe left its window BA to the next one
  double scene_depth = 1.0;            // median depth of the map seen from the camera, map units
  // map persistence (system_map_io.cpp)
  bool localization_only = false;  // the map is not changed (System::setLocalizationOnly)
  bool map_loaded = false;         // the map came from loadMap() (a loss is then never given up)
  RunCounters counters;
  std::vector<TrajectoryEntry> trajectory;
  std::vector<std::uint64_t> prev_mapped_ids;  // tracks with a map point at the end of the last tracked frame
  TrackSurvival track_survival;                // the share of them the recent frames kept
  // both threads (StageTimings is thread-safe)
  StageTimings timings;
  // made by the mapping thread after each frame, read by the tracking thread
  std::mutex prior_mutex;
  std::condition_variable prior_cv;
  std::shared_ptr<const TrackPriorSource> prior_source;
  // prior_source when the last frame's priors were counted out: what the next frame's tracker
  // reads, early priors even if the frame's end replaced them meanwhile (a pipelined tracker
  // then reads the same priors whatever the threads' timing).
  std::shared_ptr<const TrackPriorSource> counted_prior_source;
  std::uint64_t prior_frames = 0;  // mapFrame calls whose priors are out (early or at their end)
  bool priors_out_early = false;   // this frame's went out once its pose was found
  void publishPriorSource(const FrameResult& result);
  // As soon as the frame's pose is found: its map tracks and the motion, before the keyframe's
  // triangulation and window BA (a pipelined tracker waiting for them goes on meanwhile).
  void publishEarlyPriors(const FrameContext& frame);
  void markPriorsOut();  // the frame's priors are out (once per mapFrame call)
  void clearPriorSource();
  void setPriorSource(std::shared_ptr<const TrackPriorSource> source);  // under prior_mutex
  // The motion and the map points of these tracks (sorted ids; tracks without one are left out).
  std::shared_ptr<const TrackPriorSource> priorSourceOf(const std::vector<std::uint64_t>& ids) const;
};

}  // namespace vitamin_e::pipeline
