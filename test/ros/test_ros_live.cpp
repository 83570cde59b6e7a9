// Live.* (live.test): a bag played as a live camera (no clock, faster than recorded) into the
// pipelined tracker: frames are dropped and tracking goes on, and the services that read the
// map work while frames are in the pipeline. Correctness only (poses, no relocalization, frame
// order); how fast is scripts/bench_live.sh's.
#include <algorithm>
#include <string>
#include <vector>

#include <geometry_msgs/PoseStamped.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <std_srvs/SetBool.h>
#include <std_srvs/Trigger.h>

#include "ros_test_helpers.h"
#include "vitamin_e/SaveFile.h"
#include "vitamin_e/TrackingStatus.h"
#include "vitamin_e/eval/metrics.h"
#include "vitamin_e/eval/trajectory.h"
#include "vitamin_e/map/map_file.h"

using vitamin_e_test::privateParam;
using vitamin_e_test::Watcher;

TEST(Live, PipelinedTrackingGoesOnWithDroppedFrames) {
  namespace eval = vitamin_e::eval;
  ros::NodeHandle nh;
  Watcher<vitamin_e::TrackingStatus> status(nh, "/tracking/status", 1000);
  Watcher<geometry_msgs::PoseStamped> poses(nh, "/tracking/pose", 1000);
  const eval::Trajectory truth = eval::readTum(privateParam("data_dir") + "/long_groundtruth.tum");
  const std::size_t frames = std::stoul(privateParam("frames", "200"));
  ASSERT_EQ(truth.size(), frames);
  ASSERT_TRUE(ros::service::waitForService("/tracking/save_trajectory", ros::Duration(30.0)));
  ASSERT_TRUE(status.waitForPublisher(30.0));
  ASSERT_TRUE(poses.waitForPublisher(30.0));
  ASSERT_TRUE(ros::service::waitForService("/player/pause_playback", ros::Duration(30.0)));
  std_srvs::SetBool resume;
  resume.request.data = false;
  ASSERT_TRUE(ros::service::call("/player/pause_playback", resume));

  // The services that read the map wait for the pipeline's frames while the bag goes on.
  ASSERT_TRUE(status.waitFor([](const auto& m) { return !m.empty() && m.back()->frames_tracked >= 30; }, 60.0));
  vitamin_e::SaveFile save_map;
  save_map.request.path = privateParam("output_dir", "/tmp") + "/live_map.vemap";
  ASSERT_TRUE(ros::service::call("/tracking/save_map", save_map));
  EXPECT_TRUE(save_map.response.success) << save_map.response.message;
  EXPECT_NO_THROW(vitamin_e::map::loadMapFile(save_map.request.path));
  vitamin_e::SaveFile points;
  points.request.path = privateParam("output_dir", "/tmp") + "/live_points.ply";
  ASSERT_TRUE(ros::service::call("/tracking/export_points", points));
  EXPECT_TRUE(points.response.success) << points.response.message;

  // The last image is always processed (nothing newer replaces it in the live queue).
  const double last_stamp = truth.back().t;
  ASSERT_TRUE(status.waitFor(
      [&](const auto& s) { return !s.empty() && s.back()->header.stamp.toSec() >= last_stamp - 1e-6; }, 60.0))
      << "the last frame's status did not come";
  const auto s = status.messages();
  const vitamin_e::TrackingStatus& last = *s.back();
  const std::size_t processed = last.frames_processed;
  std::printf("live: %zu of %zu frames processed, %llu tracked, %d relocalizations, %d init retries\n", processed,
              frames, static_cast<unsigned long long>(last.frames_tracked), last.relocalizations, last.init_retries);
  EXPECT_LT(processed, frames) << "no frame was dropped: the test does not test what it says";
  EXPECT_GE(processed, frames / 4);
  EXPECT_EQ(last.relocalizations, 0) << last.message;
  EXPECT_EQ(last.init_retries, 0) << last.message;
  EXPECT_EQ(last.segment, 1u);
  EXPECT_EQ(last.map, 1u);
  EXPECT_EQ(last.state, vitamin_e::TrackingStatus::TRACKING) << last.state_name << ": " << last.message;
  // The initialization takes the first few frames processed; every frame after it is tracked.
  EXPECT_GE(last.frames_tracked + 8, processed);
  // Results come in frame order through the two threads.
  for (std::size_t k = 1; k < s.size(); ++k) {
    ASSERT_LT(s[k - 1]->header.stamp, s[k]->header.stamp) << "status " << k << " out of order";
  }
  // One pose for every tracked frame, published once (before the frame's map work, when it is
  // tracked from the map; with its status otherwise), in frame order.
  std::vector<ros::Time> tracked_stamps;
  for (const auto& m : s) {
    if (m->state == vitamin_e::TrackingStatus::TRACKING) tracked_stamps.push_back(m->header.stamp);
  }
  ASSERT_TRUE(poses.waitFor([&](const auto& m) { return m.size() >= tracked_stamps.size(); }, 10.0));
  const auto p = poses.messages();
  for (std::size_t k = 1; k < p.size(); ++k) {
    ASSERT_LT(p[k - 1]->header.stamp, p[k]->header.stamp) << "pose " << k << " out of order (or twice)";
  }
  std::vector<ros::Time> pose_stamps;
  pose_stamps.reserve(p.size());
  for (const auto& m : p) pose_stamps.push_back(m->header.stamp);
  EXPECT_EQ(pose_stamps, tracked_stamps);

  // The poses against the ground truth (Sim(3)-aligned), over the frames processed.
  vitamin_e::SaveFile save;
  save.request.path = privateParam("output_dir", "/tmp") + "/live_trajectory.txt";
  ASSERT_TRUE(ros::service::call("/tracking/save_trajectory", save));
  ASSERT_TRUE(save.response.success) << save.response.message;
  const eval::Trajectory estimate = eval::readTum(save.request.path);
  eval::EvalConfig config;
  config.frames = processed;
  eval::EvalResult result;
  ASSERT_NO_THROW(result = eval::evaluate(estimate, truth, config)) << estimate.size() << " poses saved";
  ROS_INFO_STREAM("live trajectory vs ground truth:\n" << eval::summary(result, config));
  RecordProperty("ate_rmse_m", std::to_string(result.ate.rmse));
  EXPECT_LT(result.ate.rmse, std::stod(privateParam("max_ate_m", "0.003")));

  std_srvs::Trigger reset;
  ASSERT_TRUE(ros::service::call("/tracking/reset", reset));
  EXPECT_TRUE(reset.response.success) << reset.response.message;
}
