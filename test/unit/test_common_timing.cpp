// common/timing.h: percentiles, the per-stage samples and their table, and the scoped timer's
// bookkeeping (what it records and where; never how long anything took).
#include <gtest/gtest.h>

#include <cmath>
#include <sstream>
#include <thread>
#include <vector>

#include "vitamin_e/common/timing.h"

using vitamin_e::percentile;
using vitamin_e::ScopedTimer;
using vitamin_e::StageTimings;
using vitamin_e::upperMedian;

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
}

// A node that runs for days adds a sample per frame and stage: the memory stays
// bounded, the count and mean exact, the percentiles from samples spread over the
// whole run (not only its start or its end).
TEST(StageTimings, KeepsABoundedEvenlySpreadShareOfALongRun) {
  StageTimings t(1000);
  const std::size_t n = 100000;
  // A run whose later half is slower: a kept share from one end only would miss it.
  for (std::size_t i = 0; i < n; ++i) {
    const double ms = static_cast<double>(i % 100);
    t.add("tracking", i < n / 2 ? ms : 100.0 + ms);
  }
  const std::vector<double> kept = t.samples("tracking");
  EXPECT_LE(kept.size(), 1000u);
  EXPECT_GE(kept.size(), 500u);
  const vitamin_e::TimingSummary s = t.summary("tracking");
  EXPECT_EQ(s.count, n);
  EXPECT_NEAR(s.mean_ms, 99.5, 1e-9);  // exact: (49.5 + 149.5) / 2
  EXPECT_NEAR(s.median_ms, 100.0, 2.0);
  EXPECT_NEAR(s.p95_ms, 190.0, 3.0);
  std::size_t slow = 0;
  for (double ms : kept) slow += ms >= 100.0;
  EXPECT_NEAR(static_cast<double>(slow) / static_cast<double>(kept.size()), 0.5, 0.01);
  // Handed on whole (the dense mapper's mesh times into a run's table): the same figures.
  StageTimings report;
  report.add("ba", 1.0);
  report.addStage("tracking", t);
  EXPECT_EQ(report.summary("tracking").count, n);
  EXPECT_DOUBLE_EQ(report.summary("tracking").mean_ms, s.mean_ms);
  EXPECT_DOUBLE_EQ(report.summary("tracking").median_ms, s.median_ms);
  ASSERT_EQ(report.stages().size(), 2u);
  EXPECT_EQ(report.stages()[1], "tracking");
  // Below the bound every sample is kept, in order.
  StageTimings small(1000);
  for (int i = 0; i < 1000; ++i) small.add("ba", i);
  ASSERT_EQ(small.samples("ba").size(), 1000u);
  EXPECT_EQ(small.samples("ba")[999], 999.0);
}

TEST(Percentile, UpperMedianTakesTheMiddleElementWithoutInterpolating) {
  EXPECT_DOUBLE_EQ(upperMedian({}), 0.0);
  EXPECT_DOUBLE_EQ(upperMedian({4.0, 1.0, 3.0}), 3.0);
  EXPECT_DOUBLE_EQ(upperMedian({4.0, 1.0, 3.0, 2.0}), 3.0);  // element 2 of 1 2 3 4
}

TEST(StageTimings, TableHasOneLinePerStageWithItsNumbers) {
  StageTimings t;
  for (double ms : {1.0, 2.0, 3.0, 4.0, 10.0}) t.add("ba", ms);
  t.add("tracking", 2.5);
  const std::string table = t.table();
  std::istringstream in(table);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  ASSERT_EQ(lines.size(), 3u) << table;
  EXPECT_EQ(lines[0].rfind("stage", 0), 0u) << lines[0];
  // ba: mean 4, median 3, p95 8.8 (interpolated between 4 and 10), 5 samples; in first-seen order.
  std::istringstream ba(lines[1]);
  std::string name;
  double mean = 0, median = 0, p95 = 0;
  std::size_t count = 0;
  ba >> name >> mean >> median >> p95 >> count;
  EXPECT_EQ(name, "ba");
  EXPECT_DOUBLE_EQ(mean, 4.0);
  EXPECT_DOUBLE_EQ(median, 3.0);
  EXPECT_DOUBLE_EQ(p95, 8.8);
  EXPECT_EQ(count, 5u);
  EXPECT_EQ(lines[2].rfind("tracking", 0), 0u) << lines[2];
  // A chosen subset in a chosen order; a stage without samples shows count 0.
  const std::string some = t.table({"tracking", "missing"});
  EXPECT_LT(some.find("tracking"), some.find("missing"));
  EXPECT_EQ(some.find("ba "), std::string::npos) << some;
}

TEST(StageTimings, CopiesAndClears) {
  StageTimings t;
  t.add("a", 1.0);
  StageTimings copy(t);
  t.add("a", 3.0);
  EXPECT_EQ(copy.summary("a").count, 1u);
  copy = t;
  EXPECT_EQ(copy.samples("a"), (std::vector<double>{1.0, 3.0}));
  t.clear();
  EXPECT_TRUE(t.stages().empty());
  EXPECT_EQ(copy.summary("a").count, 2u);
}

TEST(StageTimings, SamplesFromSeveralThreadsAreAllKept) {
  StageTimings t;
  std::vector<std::thread> threads;
  threads.reserve(4);
  for (int k = 0; k < 4; ++k) {
    threads.emplace_back([&t, k] {
      for (int i = 0; i < 1000; ++i) t.add(k % 2 ? "mapping" : "tracking", 1.0);
    });
  }
  for (auto& th : threads) th.join();
  EXPECT_EQ(t.summary("tracking").count, 2000u);
  EXPECT_EQ(t.summary("mapping").count, 2000u);
  EXPECT_EQ(t.stages().size(), 2u);
}

TEST(ScopedTimer, RecordsOnceInTheStageAndTheFramesTimes) {
  StageTimings t;
  std::map<std::string, double> frame_ms;
  double recorded = -1.0;
  {
    ScopedTimer timer(&t, "pose", &frame_ms);
    recorded = timer.stop();
    EXPECT_EQ(timer.stop(), recorded) << "a second stop() returns the first measure";
  }  // the destructor adds nothing after stop()
  ASSERT_EQ(t.samples("pose").size(), 1u);
  EXPECT_EQ(t.samples("pose")[0], recorded);
  EXPECT_EQ(frame_ms.at("pose"), recorded);
  EXPECT_GE(recorded, 0.0);
  { ScopedTimer timer(&t, "pose"); }  // stopped by its destructor, no frame map
  EXPECT_EQ(t.summary("pose").count, 2u);
  EXPECT_EQ(frame_ms.size(), 1u);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
