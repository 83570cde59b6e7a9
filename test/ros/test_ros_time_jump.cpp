// rostests of one map across time jumps:
//   TimeJump.* (time_jump.test) the test bag's images published into a tracker, then its last
//       1.5 s again with their own stamps (a bag, then a bag of its end: the camera comes back
//       somewhere other than where the map began). The second pass must be in the first
//       pass's map: the first pass's Sim(3) to the ground truth fits it too, and tf's map
//       frame does not move.
//   Loop.* (loop.test) the bag played with rosbag play --loop: the same, with rosbag play.
#include <algorithm>
#include <cmath>
#include <map>

#include <gtest/gtest.h>
#include <nav_msgs/Path.h>
#include <ros/ros.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/Image.h>
#include <std_srvs/SetBool.h>
#include <tf2_msgs/TFMessage.h>

#include "ros_test_helpers.h"
#include "vitamin_e/SaveFile.h"
#include "vitamin_e/TrackingStatus.h"
#include "vitamin_e/eval/metrics.h"
#include "vitamin_e/pipeline/session.h"
#include "vitamin_e/ros/conversions.h"

using vitamin_e_test::Watcher;
using Statuses = std::vector<vitamin_e::TrackingStatus::ConstPtr>;
namespace eval = vitamin_e::eval;
using vitamin_e::pipeline::TrajectorySegment;

namespace {

std::size_t processed(const Statuses& s) { return s.empty() ? 0 : s.back()->frames_processed; }

eval::Trajectory toEval(const TrajectorySegment& s) {
  eval::Trajectory t;
  for (const auto& e : s.poses) t.push_back({e.timestamp, e.T_w_c});
  return t;
}

std::vector<TrajectorySegment> saveTrajectory(const std::string& name) {
  vitamin_e::SaveFile save;
  save.request.path = vitamin_e_test::privateParam("output_dir", "/tmp") + "/" + name + "_trajectory.txt";
  EXPECT_TRUE(ros::service::call("/tracking/save_trajectory", save));
  EXPECT_TRUE(save.response.success) << save.response.message;
  return vitamin_e::pipeline::readSegmentsTum(save.request.path);
}

// The second segment is in the first one's map: in the same map number, and the Sim(3) that
// aligns the first segment to the ground truth aligns the second as well as its own does
// (within 1.5x of the larger of the two segments' own ATEs; a new map, placed and scaled
// anew, is off by a large part of the path).
void expectSameMap(const std::vector<TrajectorySegment>& segments, std::size_t min_poses) {
  ASSERT_GE(segments.size(), 2u);
  EXPECT_EQ(segments[0].map, segments[1].map) << "the second segment is in a new map: " << segments[1].note;
  EXPECT_NE(segments[1].note.find("time jump"), std::string::npos) << segments[1].note;
  EXPECT_GE(segments[0].poses.size(), min_poses);
  EXPECT_GE(segments[1].poses.size(), min_poses / 2);
  const eval::Trajectory truth = eval::readTum(vitamin_e_test::privateParam("data_dir") + "/groundtruth.tum");
  eval::EvalConfig config;
  config.frames = truth.size();
  const eval::EvalResult first = eval::evaluate(toEval(segments[0]), truth, config);
  const eval::EvalResult second_own = eval::evaluate(toEval(segments[1]), truth, config);
  config.given_alignment = first.alignment;
  const eval::EvalResult second_in_first = eval::evaluate(toEval(segments[1]), truth, config);
  ::testing::Test::RecordProperty("ate_first_m", std::to_string(first.ate.rmse));
  ::testing::Test::RecordProperty("ate_second_own_m", std::to_string(second_own.ate.rmse));
  ::testing::Test::RecordProperty("ate_second_in_first_m", std::to_string(second_in_first.ate.rmse));
  ROS_INFO("ATE: first segment %.5f m, second %.5f m with its own Sim(3), %.5f m with the first's (path %.3f m)",
           first.ate.rmse, second_own.ate.rmse, second_in_first.ate.rmse, first.path_length_m);
  EXPECT_LT(first.ate.rmse, 0.01);
  EXPECT_LE(second_in_first.ate.rmse, 1.5 * std::max(first.ate.rmse, second_own.ate.rmse))
      << "the second segment does not fit the first one's alignment: a map of its own";
}

// map -> camera on tf at each stamp, in the order they were sent (a stamp twice: both passes).
std::map<double, std::vector<Eigen::Isometry3d>> mapToCamera(const std::vector<tf2_msgs::TFMessage::ConstPtr>& tf) {
  std::map<double, std::vector<Eigen::Isometry3d>> out;
  for (const auto& m : tf) {
    for (const auto& t : m->transforms) {
      if (t.header.frame_id == "map" && t.child_frame_id == "cam0") {
        out[t.header.stamp.toSec()].push_back(vitamin_e_ros::fromTransformMsg(t.transform));
      }
    }
  }
  return out;
}

// tf's map frame does not re-anchor: a frame seen in both passes is published at (nearly)
// the same place both times; a re-anchored map puts the second pass's first camera at the
// origin, off by the distance the camera had travelled.
void expectMapFrameKept(const std::map<double, std::vector<Eigen::Isometry3d>>& published) {
  double extent = 0.0, worst = 0.0;
  int twice = 0;
  Eigen::Vector3d first_position = Eigen::Vector3d::Zero();
  bool have_first = false;
  for (const auto& kv : published) {
    const Eigen::Vector3d p = kv.second.front().translation();
    if (!have_first) first_position = p, have_first = true;
    extent = std::max(extent, (p - first_position).norm());
    if (kv.second.size() < 2) continue;
    ++twice;
    worst = std::max(worst, (kv.second[1].translation() - p).norm());
  }
  ROS_INFO("map -> cam0 of %d frames published in both passes: %.5f apart at most (extent of the path %.3f)", twice,
           worst, extent);
  EXPECT_GE(twice, 10) << "too few frames published in both passes";
  EXPECT_LT(worst, 0.05 * extent) << "tf's map frame moved at the time jump";
}

}  // namespace

TEST(TimeJump, BagThenItsEndStaysInTheMap) {
  ros::NodeHandle nh;
  std::vector<sensor_msgs::Image::ConstPtr> images;
  {
    rosbag::Bag bag(vitamin_e_test::privateParam("data_dir") + "/sequence.bag");
    for (const rosbag::MessageInstance& m : rosbag::View(bag)) {
      if (auto img = m.instantiate<sensor_msgs::Image>()) images.push_back(img);
    }
  }
  ASSERT_GE(images.size(), 40u);
  Watcher<vitamin_e::TrackingStatus> status(nh, "/tracking/status", 1000);
  Watcher<tf2_msgs::TFMessage> tf(nh, "/tf", 5000);
  ros::Publisher pub = nh.advertise<sensor_msgs::Image>("/cam0/image_raw", 1000);
  ASSERT_TRUE(status.waitForPublisher(30.0));
  const auto deadline = ros::WallTime::now() + ros::WallDuration(30.0);
  while (pub.getNumSubscribers() == 0 && ros::WallTime::now() < deadline) ros::WallDuration(0.02).sleep();
  ASSERT_GT(pub.getNumSubscribers(), 0u);
  const std::size_t n = images.size();
  for (const auto& img : images) {
    pub.publish(img);
    ros::WallDuration(0.005).sleep();
  }
  ASSERT_TRUE(status.waitFor([&](const Statuses& s) { return processed(s) >= n; }, 120.0))
      << "first pass: processed " << processed(status.messages()) << " of " << n;
  // The last 1.5 s again, with their stamps: 1.5 s back in time (more than ~time_jump_threshold).
  const std::size_t from = n / 2;
  for (std::size_t i = from; i < n; ++i) {
    pub.publish(images[i]);
    ros::WallDuration(0.005).sleep();
  }
  ASSERT_TRUE(status.waitFor([&](const Statuses& s) { return processed(s) >= n + (n - from); }, 120.0))
      << "second pass: processed " << processed(status.messages());
  const auto s = status.messages();
  EXPECT_EQ(s.back()->segment, 2u);
  EXPECT_EQ(s.back()->map, 1u);
  EXPECT_GE(s.back()->relocalizations, 1);
  expectSameMap(saveTrajectory("time_jump"), n / 2);
  expectMapFrameKept(mapToCamera(tf.messages()));
}

// The bag played with --loop: at the second pass the stamps jump back; the second pass is
// tracked in the first pass's map (relocalized at the bag's first frames), and the path starts
// over at the jump.
TEST(Loop, SecondPassInTheFirstMap) {
  ros::NodeHandle nh;
  const std::size_t frames = std::stoul(vitamin_e_test::privateParam("frames", "60"));
  Watcher<vitamin_e::TrackingStatus> status(nh, "/tracking/status", 5000);
  Watcher<nav_msgs::Path> path(nh, "/tracking/path", 5000);
  Watcher<tf2_msgs::TFMessage> tf(nh, "/tf", 10000);
  ASSERT_TRUE(status.waitForPublisher(30.0));
  ASSERT_TRUE(path.waitForPublisher(30.0));
  ASSERT_TRUE(ros::service::waitForService("/player/pause_playback", ros::Duration(30.0)));
  std_srvs::SetBool pause;
  pause.request.data = false;
  ASSERT_TRUE(ros::service::call("/player/pause_playback", pause));
  // Most of the second pass processed (frames queue in the tracker: every frame is processed).
  EXPECT_TRUE(status.waitFor(
      [&](const Statuses& s) { return !s.empty() && s.back()->segment >= 2 && processed(s) >= 2 * frames - 5; }, 150.0))
      << "frames processed " << processed(status.messages());
  pause.request.data = true;
  ASSERT_TRUE(ros::service::call("/player/pause_playback", pause));
  const auto s = status.messages();
  ASSERT_FALSE(s.empty());
  EXPECT_EQ(s.back()->map, 1u) << "a new map at the loop";
  expectSameMap(saveTrajectory("loop"), frames / 2);
  expectMapFrameKept(mapToCamera(tf.messages()));
  // The path: poses in the first pass, then an empty path when the second begins.
  const auto paths = path.messages();
  bool grown = false, cleared = false;
  for (const auto& p : paths) {
    if (p->poses.size() > 10) grown = true;
    if (grown && p->poses.empty()) cleared = true;
  }
  EXPECT_TRUE(cleared) << "the path was not cleared at the time jump (" << paths.size() << " path messages)";
}
