#include "vitamin_e/pipeline/recovery.h"

#include <stdexcept>
#include <string>

namespace vitamin_e::pipeline {

namespace {

using S = TrackingState;
using R = StateReason;
using A = RecoveryAction;

Transition to(S state, S frame_state, R reason, A action = A::kNone) { return {state, frame_state, reason, action}; }

const char* eventName(RecoveryEvent e) {
  switch (e) {
    case RecoveryEvent::kSkipped: return "skipped";
    case RecoveryEvent::kNoMapYet: return "no map yet";
    case RecoveryEvent::kMapBuilt: return "map built";
    case RecoveryEvent::kPoseFound: return "pose found";
    case RecoveryEvent::kPoseFailed: return "pose failed";
    case RecoveryEvent::kPoseJumped: return "pose jumped";
    case RecoveryEvent::kRelocalized: return "relocalized";
    case RecoveryEvent::kNotRelocalized: return "not relocalized";
  }
  return "unknown";
}

}  // namespace

Transition transition(TrackingState state, RecoveryEvent event, const RecoveryGuards& guards) {
  if (event == RecoveryEvent::kSkipped && state != S::kLost) return to(state, state, R::kSkipped);
  switch (state) {
    case S::kInitializing:
      if (event == RecoveryEvent::kNoMapYet) return to(S::kInitializing, S::kInitializing, R::kWaitingForMap);
      if (event == RecoveryEvent::kMapBuilt) return to(S::kTracking, S::kTracking, R::kInitialized);
      break;
    case S::kTracking:
      if (event == RecoveryEvent::kPoseFound) return to(S::kTracking, S::kTracking, R::kTracked);
      // A loss: the camera is looked for in the map when there is one to look in,
      // else a new map starts. A failed pose's frame is searched for at once and
      // is the new map's reference; a jumped one is neither: the per-frame BA has
      // already moved its points with the jumped pose.
      if (event == RecoveryEvent::kPoseFailed) {
        return guards.can_relocalize ? to(S::kRelocalizing, S::kLost, R::kPoseFailed, A::kRelocalizeNow)
                                     : to(S::kInitializing, S::kLost, R::kPoseFailed, A::kNewMapFromFrame);
      }
      if (event == RecoveryEvent::kPoseJumped) {
        return guards.can_relocalize ? to(S::kRelocalizing, S::kLost, R::kPoseJumped)
                                     : to(S::kInitializing, S::kLost, R::kPoseJumped, A::kNewMap);
      }
      break;
    case S::kRelocalizing:
      if (event == RecoveryEvent::kRelocalized) return to(S::kTracking, S::kTracking, R::kRelocalized);
      if (event == RecoveryEvent::kNotRelocalized) {
        return guards.wait_over ? to(S::kInitializing, S::kLost, R::kRelocalizationTimedOut, A::kNewMapFromFrame)
                                : to(S::kRelocalizing, S::kRelocalizing, R::kNotRelocalized);
      }
      break;
    case S::kLost: break;
  }
  throw std::logic_error(std::string("Recovery: no transition from ") + toString(state) + " on '" + eventName(event) +
                         "'");
}

Transition Recovery::apply(RecoveryEvent event, const RecoveryFacts& facts) {
  RecoveryGuards guards;
  guards.can_relocalize = facts.index_available || facts.keep_map;
  if (event == RecoveryEvent::kNotRelocalized && state_ == S::kRelocalizing) {
    if (static_cast<long long>(facts.frame_tracks) >= config_.min_frame_tracks) ++lost_frames_;
    guards.wait_over = lost_frames_ >= config_.max_lost_frames && !facts.keep_map;
  }
  const Transition t = transition(state_, event, guards);
  if (t.state == S::kRelocalizing && state_ != S::kRelocalizing) lost_frames_ = 0;  // the wait starts
  state_ = t.state;
  return t;
}

void Recovery::reset() {
  state_ = S::kInitializing;
  lost_frames_ = 0;
}

void Recovery::startRelocalizing() {
  state_ = S::kRelocalizing;
  lost_frames_ = 0;
}

}  // namespace vitamin_e::pipeline
