// pipeline::Recovery: the tracking state's transition table, every (state, event, guards)
// case, and the relocalization wait it counts.
#include <gtest/gtest.h>

#include <stdexcept>
#include <tuple>
#include <vector>

#include "vitamin_e/pipeline/recovery.h"

namespace ve = vitamin_e;
using ve::pipeline::Recovery;
using ve::pipeline::RecoveryAction;
using ve::pipeline::RecoveryConfig;
using ve::pipeline::RecoveryEvent;
using ve::pipeline::RecoveryFacts;
using ve::pipeline::RecoveryGuards;
using ve::pipeline::StateReason;
using ve::pipeline::TrackingState;
using ve::pipeline::Transition;
using ve::pipeline::transition;

namespace {

constexpr TrackingState kStates[] = {TrackingState::kInitializing, TrackingState::kTracking,
                                     TrackingState::kRelocalizing};
constexpr RecoveryEvent kEvents[] = {RecoveryEvent::kSkipped,     RecoveryEvent::kNoMapYet,
                                     RecoveryEvent::kMapBuilt,    RecoveryEvent::kPoseFound,
                                     RecoveryEvent::kPoseFailed,  RecoveryEvent::kPoseJumped,
                                     RecoveryEvent::kRelocalized, RecoveryEvent::kNotRelocalized};

RecoveryGuards guards(bool can_relocalize, bool wait_over) {
  RecoveryGuards g;
  g.can_relocalize = can_relocalize;
  g.wait_over = wait_over;
  return g;
}

struct Row {
  TrackingState state;
  RecoveryEvent event;
  bool can_relocalize;
  bool wait_over;
  TrackingState next;
  TrackingState frame_state;
  StateReason reason;
  RecoveryAction action;
};

using S = TrackingState;
using E = RecoveryEvent;
using R = StateReason;
using A = RecoveryAction;

// The table as the system relies on it; a row per guard value where the guard matters.
const std::vector<Row>& table() {
  static const std::vector<Row> rows = {
      {S::kInitializing, E::kNoMapYet, false, false, S::kInitializing, S::kInitializing, R::kWaitingForMap, A::kNone},
      {S::kInitializing, E::kMapBuilt, false, false, S::kTracking, S::kTracking, R::kInitialized, A::kNone},
      {S::kTracking, E::kPoseFound, false, false, S::kTracking, S::kTracking, R::kTracked, A::kNone},
      // A failed pose: looked for in the map at once, or a new map from this frame.
      {S::kTracking, E::kPoseFailed, true, false, S::kRelocalizing, S::kLost, R::kPoseFailed, A::kRelocalizeNow},
      {S::kTracking, E::kPoseFailed, false, false, S::kInitializing, S::kLost, R::kPoseFailed, A::kNewMapFromFrame},
      // A jumped pose: relocalized from the next frame on, or a new map from the next frame.
      {S::kTracking, E::kPoseJumped, true, false, S::kRelocalizing, S::kLost, R::kPoseJumped, A::kNone},
      {S::kTracking, E::kPoseJumped, false, false, S::kInitializing, S::kLost, R::kPoseJumped, A::kNewMap},
      {S::kRelocalizing, E::kRelocalized, true, false, S::kTracking, S::kTracking, R::kRelocalized, A::kNone},
      {S::kRelocalizing, E::kNotRelocalized, true, false, S::kRelocalizing, S::kRelocalizing, R::kNotRelocalized,
       A::kNone},
      {S::kRelocalizing, E::kNotRelocalized, true, true, S::kInitializing, S::kLost, R::kRelocalizationTimedOut,
       A::kNewMapFromFrame},
  };
  return rows;
}

bool inTable(S state, E event) {
  for (const Row& r : table()) {
    if (r.state == state && r.event == event) return true;
  }
  return false;
}

RecoveryFacts facts(bool index, bool keep_map, std::size_t tracks) {
  RecoveryFacts f;
  f.index_available = index;
  f.keep_map = keep_map;
  f.frame_tracks = tracks;
  return f;
}

}  // namespace

TEST(Recovery, TransitionTable) {
  for (const Row& r : table()) {
    const Transition t = transition(r.state, r.event, guards(r.can_relocalize, r.wait_over));
    SCOPED_TRACE(std::string(toString(r.state)) + " + event " + std::to_string(static_cast<int>(r.event)));
    EXPECT_EQ(t.state, r.next);
    EXPECT_EQ(t.frame_state, r.frame_state);
    EXPECT_EQ(t.reason, r.reason);
    EXPECT_EQ(t.action, r.action);
    // kLost is a frame's state, never the system's: the next frame initializes, tracks or relocalizes.
    EXPECT_NE(t.state, S::kLost);
  }
}

TEST(Recovery, GuardsMatterOnlyWhereTheTableSaysSo) {
  for (const S state : kStates) {
    for (const E event : kEvents) {
      if (!inTable(state, event)) continue;
      std::vector<std::tuple<S, R, A>> outcomes;
      for (const bool can : {false, true}) {
        for (const bool over : {false, true}) {
          const Transition t = transition(state, event, guards(can, over));
          outcomes.emplace_back(t.state, t.reason, t.action);
        }
      }
      const bool varies = outcomes[0] != outcomes[1] || outcomes[0] != outcomes[2] || outcomes[0] != outcomes[3];
      const bool guarded = event == E::kPoseFailed || event == E::kPoseJumped || event == E::kNotRelocalized;
      EXPECT_EQ(varies, guarded) << toString(state) << " + event " << static_cast<int>(event);
    }
  }
}

TEST(Recovery, ASkippedFrameKeepsTheState) {
  for (const S state : kStates) {
    const Transition t = transition(state, E::kSkipped, {});
    EXPECT_EQ(t.state, state);
    EXPECT_EQ(t.frame_state, state);
    EXPECT_EQ(t.reason, R::kSkipped);
    EXPECT_EQ(t.action, A::kNone);
  }
}

TEST(Recovery, AnEventTheStateCannotHaveIsABug) {
  int refused = 0;
  for (const S state : kStates) {
    for (const E event : kEvents) {
      if (event == E::kSkipped || inTable(state, event)) continue;
      EXPECT_THROW(transition(state, event, guards(true, false)), std::logic_error)
          << toString(state) << " + event " << static_cast<int>(event);
      ++refused;
    }
  }
  EXPECT_EQ(refused, 3 * 7 - 7);  // 7 events besides kSkipped, 7 (state, event) pairs in the table
  EXPECT_THROW(transition(S::kLost, E::kSkipped, {}), std::logic_error);
}

TEST(Recovery, TheWaitCountsFramesWithFeaturesAndEndsInANewMap) {
  RecoveryConfig config;
  config.max_lost_frames = 3;
  config.min_frame_tracks = 100;
  Recovery recovery(config);
  EXPECT_EQ(recovery.state(), S::kInitializing);
  EXPECT_EQ(recovery.apply(E::kMapBuilt, facts(true, false, 500)).reason, R::kInitialized);
  EXPECT_EQ(recovery.apply(E::kPoseFailed, facts(true, false, 500)).action, A::kRelocalizeNow);
  EXPECT_EQ(recovery.state(), S::kRelocalizing);
  EXPECT_EQ(recovery.lostFrames(), 0) << "the loss frame does not count";
  // Black frames (too few tracks) do not use up the wait.
  for (int i = 0; i < 10; ++i)
    EXPECT_EQ(recovery.apply(E::kNotRelocalized, facts(true, false, 5)).reason, R::kNotRelocalized);
  EXPECT_EQ(recovery.lostFrames(), 0);
  EXPECT_EQ(recovery.apply(E::kNotRelocalized, facts(true, false, 100)).reason, R::kNotRelocalized);
  EXPECT_EQ(recovery.apply(E::kNotRelocalized, facts(true, false, 100)).reason, R::kNotRelocalized);
  const Transition over = recovery.apply(E::kNotRelocalized, facts(true, false, 100));
  EXPECT_EQ(over.reason, R::kRelocalizationTimedOut);
  EXPECT_EQ(over.action, A::kNewMapFromFrame);
  EXPECT_EQ(over.frame_state, S::kLost);
  EXPECT_EQ(recovery.state(), S::kInitializing);
}

TEST(Recovery, AMapThatMustBeKeptIsSearchedForever) {
  RecoveryConfig config;
  config.max_lost_frames = 2;
  config.min_frame_tracks = 10;
  Recovery recovery(config);
  recovery.startRelocalizing();  // a loaded map
  for (int i = 0; i < 20; ++i) {
    EXPECT_EQ(recovery.apply(E::kNotRelocalized, facts(true, true, 100)).reason, R::kNotRelocalized) << i;
  }
  EXPECT_EQ(recovery.apply(E::kRelocalized, facts(true, true, 100)).state, S::kTracking);
  // Lost again without an index: the kept map is still looked for, not replaced.
  EXPECT_EQ(recovery.apply(E::kPoseFailed, facts(false, true, 100)).state, S::kRelocalizing);
}

TEST(Recovery, ANewLossStartsANewWait) {
  RecoveryConfig config;
  config.max_lost_frames = 2;
  config.min_frame_tracks = 10;
  Recovery recovery(config);
  recovery.apply(E::kMapBuilt, facts(true, false, 100));
  recovery.apply(E::kPoseJumped, facts(true, false, 100));
  recovery.apply(E::kNotRelocalized, facts(true, false, 100));
  EXPECT_EQ(recovery.lostFrames(), 1);
  recovery.apply(E::kRelocalized, facts(true, false, 100));
  recovery.apply(E::kPoseFailed, facts(true, false, 100));
  EXPECT_EQ(recovery.lostFrames(), 0);
  EXPECT_EQ(recovery.apply(E::kNotRelocalized, facts(true, false, 100)).reason, R::kNotRelocalized);
  recovery.reset();
  EXPECT_EQ(recovery.state(), S::kInitializing);
  EXPECT_EQ(recovery.lostFrames(), 0);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
