#pragma once
// The tracking state and its transitions: the one place that decides what the
// next frame does (initialize, track or relocalize) and why a frame is in its
// state. System tells what happened to a frame (an event) and carries out the
// action the transition asks for (look for the frame in the map at once, give
// the map up for a new one); it never sets a state itself.
#include "vitamin_e/pipeline/frame_result.h"

namespace vitamin_e::pipeline {

// What happened to a frame, as told by the step that handled it.
enum class RecoveryEvent {
  kSkipped,         // any state: the frame was not processed (its stamp did not increase)
  kNoMapYet,        // initializing: the initializer needs more frames, or may not build a map
  kMapBuilt,        // initializing: the initializer built a map
  kPoseFound,       // tracking: a pose from the map
  kPoseFailed,      // tracking: no pose from the tracked map points
  kPoseJumped,      // tracking: the pose moved far beyond the scene depth
  kRelocalized,     // relocalizing: found in the map
  kNotRelocalized,  // relocalizing: not found at this frame
};

// What System does on a transition besides reporting it.
enum class RecoveryAction {
  kNone,
  kRelocalizeNow,    // look for the frame that lost the camera in the map at once (no frame goes without a pose)
  kNewMap,           // give the map (and its index) up: the next frames initialize a new one
  kNewMapFromFrame,  // the same, with this frame as the new map's reference
};

// The facts a transition depends on besides the state and the event.
struct RecoveryGuards {
  // There is something to look for the camera in (a keyframe indexed by the
  // relocalizer), or a map that must not be given up (loaded, localization only).
  bool can_relocalize = false;
  // Relocalization waited long enough (relocalization.max_frames frames with
  // features) and the map may be given up.
  bool wait_over = false;
};

struct Transition {
  TrackingState state = TrackingState::kInitializing;        // after the frame: what the next frame does
  TrackingState frame_state = TrackingState::kInitializing;  // this frame's (FrameResult::state)
  StateReason reason = StateReason::kWaitingForMap;          // why (FrameResult::reason)
  RecoveryAction action = RecoveryAction::kNone;
};

// The table. state is kInitializing, kTracking or kRelocalizing (kLost is a
// frame's state only); an event the state cannot have (kPoseFound while
// initializing, ...) is a bug of the caller: std::logic_error.
Transition transition(TrackingState state, RecoveryEvent event, const RecoveryGuards& guards);

// The frame counts Recovery keeps and the facts of the system it is given.
struct RecoveryConfig {
  int max_lost_frames = 30;    // relocalization.max_frames
  int min_frame_tracks = 200;  // pipeline.min_init_tracks: a poorer frame (black, covered) does not use up the wait
};

struct RecoveryFacts {
  bool index_available = false;  // the relocalizer holds a keyframe
  bool keep_map = false;         // the map is never given up for a new one (loaded, localization only)
  std::size_t frame_tracks = 0;  // tracks of this frame
};

// The state between frames and the relocalization wait.
class Recovery {
 public:
  explicit Recovery(const RecoveryConfig& config) : config_(config) {}
  TrackingState state() const { return state_; }
  // The frame's event: the wait is counted (kNotRelocalized), the guards
  // evaluated, the transition taken and returned.
  Transition apply(RecoveryEvent event, const RecoveryFacts& facts);
  void reset();                                    // no map: initialize
  void startRelocalizing();                        // a map was loaded: look for the camera in it
  int lostFrames() const { return lost_frames_; }  // the wait so far

 private:
  RecoveryConfig config_;
  TrackingState state_ = TrackingState::kInitializing;
  int lost_frames_ = 0;  // frames with features spent relocalizing since the loss
};

}  // namespace vitamin_e::pipeline
