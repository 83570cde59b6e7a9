// The share of the last frame's map tracks a frame keeps, judged against the
// recent frames: a drone keeps about 90 %, a car at speed about 45 %; a cut
// keeps a small part of either.
#include <gtest/gtest.h>

#include <stdexcept>

#include "vitamin_e/pipeline/track_survival.h"

using vitamin_e::pipeline::TrackSurvival;

TEST(TrackSurvival, NothingCollapsesBeforeAnyFrame) {
  const TrackSurvival survival;
  EXPECT_DOUBLE_EQ(survival.usual(), 1.0);
  EXPECT_FALSE(survival.collapsed(0.0, 0.5));
}

TEST(TrackSurvival, TheUsualShareIsTheMedianOfTheRecentFrames) {
  TrackSurvival survival(5);
  for (double f : {0.9, 0.1, 0.8, 0.95, 0.85}) survival.add(f);
  EXPECT_DOUBLE_EQ(survival.usual(), 0.85);  // one bad frame does not move it
  survival.add(0.7);                         // 0.9 leaves the window
  EXPECT_EQ(survival.size(), 5u);
  EXPECT_DOUBLE_EQ(survival.usual(), 0.8);
  TrackSurvival even(4);
  for (double f : {0.2, 0.4, 0.6, 0.8}) even.add(f);
  EXPECT_DOUBLE_EQ(even.usual(), 0.5);
}

TEST(TrackSurvival, ACutCollapsesForADroneAndForACarAlike) {
  // The same 13 % survival is a cut for a drone (usually 93 %)...
  TrackSurvival drone;
  for (int i = 0; i < 10; ++i) drone.add(0.93);
  EXPECT_TRUE(drone.collapsed(0.13, 0.5));
  // ...and for a car at speed (usually 45 %), whose ordinary frames keep 39 %.
  TrackSurvival car;
  for (int i = 0; i < 10; ++i) car.add(i % 2 ? 0.40 : 0.50);
  EXPECT_FALSE(car.collapsed(0.39, 0.5));
  EXPECT_TRUE(car.collapsed(0.13, 0.5));
  EXPECT_FALSE(car.collapsed(0.13, 0.0));  // 0: never
}

TEST(TrackSurvival, ClearForgetsTheCamera) {
  TrackSurvival survival;
  survival.add(0.9);
  survival.clear();
  EXPECT_EQ(survival.size(), 0u);
  EXPECT_FALSE(survival.collapsed(0.0, 0.5));
  EXPECT_THROW(TrackSurvival(0), std::invalid_argument);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
