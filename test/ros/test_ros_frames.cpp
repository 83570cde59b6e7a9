// rostest Rep105.* (rep105.test): the tracker configured with odom and base
// frames publishes map -> odom (REP-105) such that map -> odom -> base -> camera
// is its camera pose, and never a second parent for the camera frame; runtime
// parameters change through dynamic_reconfigure.
#include <dynamic_reconfigure/Reconfigure.h>
#include <geometry_msgs/PoseStamped.h>
#include <gtest/gtest.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Log.h>
#include <std_srvs/SetBool.h>
#include <tf2_msgs/TFMessage.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <Eigen/Eigenvalues>

#include "ros_test_helpers.h"
#include "vitamin_e/TrackingStatus.h"
#include "vitamin_e/ros/conversions.h"

using vitamin_e_test::Watcher;

TEST(Rep105, MapToOdomCompletesTheCameraPose) {
  ros::NodeHandle nh;
  const int frames = std::stoi(vitamin_e_test::privateParam("frames", "60"));
  Watcher<vitamin_e::TrackingStatus> status(nh, "/tracking/status", 1000);
  Watcher<geometry_msgs::PoseStamped> pose(nh, "/tracking/pose", 1000);
  Watcher<tf2_msgs::TFMessage> tf(nh, "/tf", 1000);
  Watcher<nav_msgs::Odometry> odom(nh, "/tracking/odometry", 1000);

  // odom -> base_link (odometry, here fixed) and base_link -> cam0 (the mounting).
  Eigen::Isometry3d T_odom_base = Eigen::Isometry3d::Identity();
  T_odom_base.translation() << 1.0, -2.0, 0.0;
  T_odom_base.linear() = Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  Eigen::Isometry3d T_base_cam = Eigen::Isometry3d::Identity();
  T_base_cam.translation() << 0.2, 0.0, 0.5;
  T_base_cam.linear() << 0, 0, 1, -1, 0, 0, 0, -1, 0;  // optical camera looking along base x
  tf2_ros::StaticTransformBroadcaster static_tf;
  std::vector<geometry_msgs::TransformStamped> statics(2);
  statics[0].header.frame_id = "odom";
  statics[0].child_frame_id = "base_link";
  statics[0].transform = vitamin_e_ros::toTransformMsg(T_odom_base);
  statics[1].header.frame_id = "base_link";
  statics[1].child_frame_id = "cam0";
  statics[1].transform = vitamin_e_ros::toTransformMsg(T_base_cam);
  static_tf.sendTransform(statics);

  ASSERT_TRUE(status.waitForPublisher(30.0));
  ASSERT_TRUE(pose.waitForPublisher(30.0));
  ASSERT_TRUE(ros::service::waitForService("/player/pause_playback", ros::Duration(30.0)));
  std_srvs::SetBool resume;
  resume.request.data = false;
  ASSERT_TRUE(ros::service::call("/player/pause_playback", resume));
  EXPECT_TRUE(status.waitFor(
      [&](const auto& s) { return !s.empty() && static_cast<int>(s.back()->frames_processed) >= frames; }, 120.0));

  const auto poses = pose.messages();
  ASSERT_GT(poses.size(), 10u);
  const auto& last = poses.back();
  geometry_msgs::TransformStamped map_odom;
  bool camera_with_two_parents = false;
  ASSERT_TRUE(tf.waitFor(
      [&](const auto& msgs) {
        for (const auto& m : msgs) {
          for (const auto& t : m->transforms) {
            camera_with_two_parents |= t.header.frame_id == "map" && t.child_frame_id == "cam0";
            if (t.header.frame_id == "map" && t.child_frame_id == "odom" && t.header.stamp == last->header.stamp) {
              map_odom = t;
              return true;
            }
          }
        }
        return false;
      },
      10.0))
      << "no map -> odom at the last pose's stamp " << last->header.stamp;
  EXPECT_FALSE(camera_with_two_parents) << "map -> cam0 published although cam0 is under base_link";
  const Eigen::Isometry3d T_w_c = vitamin_e_ros::fromPoseMsg(last->pose);
  const Eigen::Isometry3d composed = vitamin_e_ros::fromTransformMsg(map_odom.transform) * T_odom_base * T_base_cam;
  EXPECT_LT((composed.matrix() - T_w_c.matrix()).cwiseAbs().maxCoeff(), 1e-5) << "map->odom->base->cam:\n"
                                                                              << composed.matrix() << "\npose:\n"
                                                                              << T_w_c.matrix();

  // ~odometry is the base's pose (child ~base_frame) with a covariance.
  ASSERT_TRUE(
      odom.waitFor([&](const auto& m) { return !m.empty() && m.back()->header.stamp == last->header.stamp; }, 10.0));
  const auto o = odom.messages().back();
  EXPECT_EQ(o->child_frame_id, "base_link");
  EXPECT_EQ(o->header.frame_id, "map");
  const Eigen::Isometry3d T_map_base = vitamin_e_ros::fromPoseMsg(o->pose.pose);
  EXPECT_LT((T_map_base.matrix() - (T_w_c * T_base_cam.inverse()).matrix()).cwiseAbs().maxCoeff(), 1e-5);
  Eigen::Matrix<double, 6, 6> C;
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 6; ++c) C(r, c) = o->pose.covariance[6 * r + c];
  using Solver = Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>>;
  EXPECT_GT(Solver(C).eigenvalues().minCoeff(), 0.0) << C;
  EXPECT_LT(C(0, 0), 1e3) << "no BA covariance on the last frame";
}

TEST(Rep105, DynamicReconfigure) {
  ASSERT_TRUE(ros::service::waitForService("/tracking/set_parameters", ros::Duration(30.0)));
  dynamic_reconfigure::Reconfigure reconfigure;
  dynamic_reconfigure::DoubleParameter period;
  period.name = "map_points_period";
  period.value = 2.5;
  reconfigure.request.config.doubles.push_back(period);
  dynamic_reconfigure::BoolParameter points;
  points.name = "publish_points";
  points.value = false;
  reconfigure.request.config.bools.push_back(points);
  ASSERT_TRUE(ros::service::call("/tracking/set_parameters", reconfigure));
  bool period_set = false, points_set = false;
  for (const auto& d : reconfigure.response.config.doubles)
    period_set |= d.name == "map_points_period" && d.value == 2.5;
  for (const auto& b : reconfigure.response.config.bools) points_set |= b.name == "publish_points" && !b.value;
  EXPECT_TRUE(period_set);
  EXPECT_TRUE(points_set);
}

// The camera -> IMU rotation checked against the gyroscope (imu_check.test): the tracker with
// the bag's own calibration says they agree; the one with a camera's calibration of another
// rig (T_BS identity, EuRoC's IMU is turned by about 90 degrees) warns that it looks wrong.
TEST(ImuCheck, WrongCameraToImuRotationWarned) {
  ros::NodeHandle nh;
  const std::size_t frames = std::stoul(vitamin_e_test::privateParam("frames", "60"));
  Watcher<vitamin_e::TrackingStatus> right(nh, "/tracking/status", 1000);
  Watcher<vitamin_e::TrackingStatus> wrong(nh, "/tracking_wrong_tbs/status", 1000);
  Watcher<rosgraph_msgs::Log> rosout(nh, "/rosout", 5000);
  ASSERT_TRUE(right.waitForPublisher(30.0));
  ASSERT_TRUE(wrong.waitForPublisher(30.0));
  ASSERT_TRUE(rosout.waitForAllPublishers(30.0));
  ASSERT_TRUE(ros::service::waitForService("/player/pause_playback", ros::Duration(30.0)));
  std_srvs::SetBool resume;
  resume.request.data = false;
  ASSERT_TRUE(ros::service::call("/player/pause_playback", resume));
  auto processed = [](const std::vector<vitamin_e::TrackingStatus::ConstPtr>& s) {
    return s.empty() ? std::size_t{0} : static_cast<std::size_t>(s.back()->frames_processed);
  };
  for (auto* w : {&right, &wrong}) {
    EXPECT_TRUE(w->waitFor([&](const auto& s) { return processed(s) + 1 >= frames; }, 200.0))
        << "processed " << processed(w->messages()) << " of " << frames;
  }
  using Log = rosgraph_msgs::Log;
  EXPECT_TRUE(vitamin_e_test::waitForLog(rosout, Log::WARN, {"looks wrong", "calibration_camera_body.yaml"}, 10.0))
      << "no warning for the wrong camera -> IMU rotation";
  EXPECT_TRUE(vitamin_e_test::waitForLog(rosout, Log::INFO, {"agrees with the gyroscope", "/calibration.yaml"}, 10.0))
      << "the right calibration was not found to agree";
  for (const auto& l : rosout.messages()) {
    EXPECT_FALSE(l->msg.find("looks wrong") != std::string::npos &&
                 l->msg.find("/calibration.yaml") != std::string::npos)
        << "the right calibration was warned about: " << l->msg;
  }
}
