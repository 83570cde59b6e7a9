#include <gtest/gtest.h>

#include <cmath>

#include "vitamin_e/common/timing.h"

using vitamin_e::percentile;
using vitamin_e::StageTimings;

TEST(Percentile, InterpolatesLinearly) {
  EXPECT_DOUBLE_EQ(percentile({}, 50.0), 0.0);
  EXPECT_DOUBLE_EQ(percentile({3.0, 1.0, 2.0}, 50.0), 2.0);
  EXPECT_DOUBLE_EQ(percentile({0.0, 10.0}, 95.0), 9.5);
  EXPECT_DOUBLE_EQ(percentile({5.0, 1.0}, 0.0), 1.0);
  EXPECT_DOUBLE_EQ(percentile({5.0, 1.0}, 100.0), 5.0);
}

TEST(FrameGapRatio, OneAtASteadyRateTheGapAfterDroppedFrames) {
  EXPECT_EQ(vitamin_e::frameGapRatio(0.05, 0.05), 1.0);
  EXPECT_EQ(vitamin_e::frameGapRatio(0.0599, 0.05), 1.0);  // jitter within the tolerance
  EXPECT_EQ(vitamin_e::frameGapRatio(0.0401, 0.05), 1.0);
  EXPECT_DOUBLE_EQ(vitamin_e::frameGapRatio(0.1, 0.05), 2.0);
  EXPECT_DOUBLE_EQ(vitamin_e::frameGapRatio(0.15, 0.05), 3.0);
  EXPECT_DOUBLE_EQ(vitamin_e::frameGapRatio(0.05, 0.15), 1.0 / 3.0);
  EXPECT_EQ(vitamin_e::frameGapRatio(std::nan(""), 0.05), 1.0);
  EXPECT_EQ(vitamin_e::frameGapRatio(0.1, 0.0), 1.0);
  EXPECT_EQ(vitamin_e::frameGapRatio(-0.1, 0.05), 1.0);
}

TEST(StageTimings, SummariesPerStageInFirstSeenOrder) {
  StageTimings t;
  t.add("tracking", 2.0);
  t.add("ba", 10.0);
  t.add("tracking", 4.0);
  ASSERT_EQ(t.stages().size(), 2u);
  EXPECT_EQ(t.stages()[0], "tracking");
  EXPECT_DOUBLE_EQ(t.summary("tracking").mean_ms, 3.0);
  EXPECT_EQ(t.summary("ba").count, 1u);
  EXPECT_EQ(t.summary("missing").count, 0u);
  EXPECT_NE(t.table().find("tracking"), std::string::npos);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
