#include <gtest/gtest.h>

#include <unistd.h>
#include <filesystem>

#include <yaml-cpp/yaml.h>

#include "vitamin_e/io/run_report.h"

using namespace vitamin_e::io;

TEST(RunReport, StatsJsonHasEveryFieldWithTheRightValues) {
  RunStats s;
  s.dataset = "/data/V1 \"01\"\\easy";
  s.dataset_kind = "euroc";
  s.init_retries = 2;
  s.wall_time_s = 2.0;
  s.addFrame(false, 100, 0, {{"tracking", 4.0}}, 5.0);
  s.addFrame(true, 300, 150, {{"tracking", 6.0}, {"ba", 20.0}}, 30.0);
  s.addFrame(true, 200, 120, {{"tracking", 5.0}, {"total", 999.0}}, 7.0);
  s.skipped_frames = 1;
  s.first_init_frame = 1;
  s.tracked_since_init = 1;
  s.reused_map_points = 17;
  s.map_points = 1234;
  s.addCounter("tracks_born", 10);
  s.addCounter("tracks_born", 30);
  s.addCounter("tracks_born", 20);
  s.addCounter("keyframe", 1);
  s.frames_by_state = {{"initializing", 1}, {"tracking", 2}};
  s.frames_by_reason = {{"waiting_for_map", 1}, {"initialized", 1}, {"tracked", 1}};
  s.dense_fused = 5;
  s.dense_dropped = 1;
  s.dense_raster_downscale = {{1, 2}, {3, 3}};
  s.peak_rss_mb = peakRssMb();
  EXPECT_GT(s.peak_rss_mb, 1.0);
  EXPECT_LT(s.peak_rss_mb, 1e5);

  // JSON is YAML: parse it back.
  const YAML::Node j = YAML::Load(toJson(s));
  EXPECT_EQ(j["dataset"].as<std::string>(), s.dataset);
  EXPECT_EQ(j["frames"].as<int>(), 3);
  EXPECT_EQ(j["tracked_frames"].as<int>(), 2);
  EXPECT_NEAR(j["success_rate"].as<double>(), 2.0 / 3.0, 1e-5);
  EXPECT_EQ(j["skipped_frames"].as<int>(), 1);
  EXPECT_EQ(j["init_retries"].as<int>(), 2);
  EXPECT_EQ(j["first_init_frame"].as<int>(), 1);
  EXPECT_EQ(j["tracked_since_init"].as<int>(), 1);
  EXPECT_EQ(j["reused_map_points"].as<int>(), 17);
  EXPECT_DOUBLE_EQ(j["success_after_init"].as<double>(), 0.5);  // 1 of the 2 frames from frame 1 on
  EXPECT_EQ(j["map_points"].as<int>(), 1234);
  EXPECT_EQ(j["frames_by_state"].size(), 2u);
  EXPECT_EQ(j["frames_by_state"]["tracking"].as<int>(), 2);
  EXPECT_EQ(j["frames_by_reason"].size(), 3u);
  EXPECT_EQ(j["frames_by_reason"]["waiting_for_map"].as<int>(), 1);
  EXPECT_FALSE(j["interrupted"].as<bool>());
  EXPECT_EQ(j["dense"]["fused"].as<int>(), 5);
  EXPECT_EQ(j["dense"]["dropped"].as<int>(), 1);
  EXPECT_EQ(j["dense"]["raster_downscale"].size(), 2u);
  EXPECT_EQ(j["dense"]["raster_downscale"]["1"].as<int>(), 2);
  EXPECT_EQ(j["dense"]["raster_downscale"]["3"].as<int>(), 3);
  EXPECT_DOUBLE_EQ(j["points_per_frame"]["mean"].as<double>(), 200.0);
  EXPECT_DOUBLE_EQ(j["points_per_frame"]["median"].as<double>(), 200.0);
  EXPECT_DOUBLE_EQ(j["mapped_points_per_frame"]["median"].as<double>(), 120.0);
  EXPECT_DOUBLE_EQ(j["timing_ms"]["tracking"]["mean"].as<double>(), 5.0);
  EXPECT_DOUBLE_EQ(j["timing_ms"]["ba"]["p95"].as<double>(), 20.0);
  // "total" is the runner's measure, never a stage reported by the system.
  EXPECT_DOUBLE_EQ(j["timing_ms"]["total"]["median"].as<double>(), 7.0);
  EXPECT_NEAR(j["timing_ms"]["total"]["p95"].as<double>(), 27.7, 1e-9);
  EXPECT_EQ(j["timing_ms"]["total"]["count"].as<int>(), 3);
  EXPECT_DOUBLE_EQ(j["fps"].as<double>(), 1.5);
  EXPECT_GT(j["peak_rss_mb"].as<double>(), 1.0);
  const YAML::Node born = j["frame_diagnostics"]["tracks_born"];
  EXPECT_DOUBLE_EQ(born["mean"].as<double>(), 20.0);
  EXPECT_DOUBLE_EQ(born["median"].as<double>(), 20.0);
  EXPECT_DOUBLE_EQ(born["min"].as<double>(), 10.0);
  EXPECT_DOUBLE_EQ(born["max"].as<double>(), 30.0);
  EXPECT_DOUBLE_EQ(born["sum"].as<double>(), 60.0);
  EXPECT_DOUBLE_EQ(j["frame_diagnostics"]["keyframe"]["sum"].as<double>(), 1.0);
  // Reports list the system's stages first and "total" last.
  const std::vector<std::string> order = reportStages(s.timing);
  EXPECT_EQ(order, (std::vector<std::string>{"tracking", "ba", "total"}));
  const std::string table = s.timing.table(order);
  EXPECT_LT(table.find("ba"), table.find("total"));
  EXPECT_NE(table.find("27.70"), std::string::npos) << table;
}

TEST(RunReport, EmptyRunIsStillValidJson) {
  RunStats s;
  s.interrupted = true;
  const YAML::Node j = YAML::Load(toJson(s));
  EXPECT_EQ(j["frames"].as<int>(), 0);
  EXPECT_DOUBLE_EQ(j["success_rate"].as<double>(), 0.0);
  EXPECT_EQ(j["first_init_frame"].as<int>(), -1);
  EXPECT_DOUBLE_EQ(j["success_after_init"].as<double>(), 0.0);
  EXPECT_TRUE(j["interrupted"].as<bool>());
  EXPECT_TRUE(j["timing_ms"].IsMap());
  EXPECT_EQ(j["timing_ms"].size(), 0u);
  EXPECT_TRUE(j["dense"]["raster_downscale"].IsMap());
  EXPECT_EQ(j["dense"]["raster_downscale"].size(), 0u);
}

TEST(RunReport, WriteFailsCleanlyOnABadPath) {
  RunStats s;
  std::string err;
  EXPECT_FALSE(writeRunStats(s, "/nonexistent_dir_ve/stats.json", &err));
  EXPECT_NE(err.find("/nonexistent_dir_ve/stats.json"), std::string::npos);
  const std::string ok = (std::filesystem::temp_directory_path() / ("ve_stats_" + std::to_string(getpid()))).string();
  EXPECT_TRUE(writeRunStats(s, ok));
  EXPECT_TRUE(std::filesystem::file_size(ok) > 10);
  std::filesystem::remove(ok);
}

TEST(RunReport, ProgressAndDurations) {
  EXPECT_EQ(formatDuration(7.2), "7s");
  EXPECT_EQ(formatDuration(245), "4m05s");
  EXPECT_EQ(formatDuration(3723), "1h02m03s");
  const std::string p = formatProgress(100, 400, 10.0, 0.5, 20);
  EXPECT_EQ(p.rfind("[#####...............] ", 0), 0u) << p;
  EXPECT_NE(p.find("100/400"), std::string::npos) << p;
  EXPECT_NE(p.find("25.0%"), std::string::npos) << p;
  EXPECT_NE(p.find("10.0 fps"), std::string::npos) << p;
  EXPECT_NE(p.find("ETA 30s"), std::string::npos) << p;
  EXPECT_NE(p.find("tracked 50%"), std::string::npos) << p;
  const std::string done = formatProgress(400, 400, 10.0, 1.0, 0);
  EXPECT_EQ(done.find('['), std::string::npos);
  EXPECT_NE(done.find("ETA 0s"), std::string::npos);
  EXPECT_EQ(jsonString("a\"b\\c\n\x01"), "\"a\\\"b\\\\c\\n\\u0001\"");
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
