// rostests of the ROS layer (one executable, one gtest suite per .test file):
//   Pipeline.*   (pipeline.test)    bag -> tracking + meshing nodelets in one manager
//   TwoProcess.* (two_process.test) tracking_node and tsdf_meshing_node, two processes
//   BadInput.*   (bad_input.test)   wrong encoding / size / stamp: errors logged, no crash
//   ShutdownSave.* (shutdown_save.test) ~trajectory_file / ~map_file (the PLY export) written when the nodelet unloads,
//                also while its SLAM thread holds a frame and its queue is full
//   Threads.*    (threads.test, test_ros_threads.cpp) services and reconfigure beside a slow SLAM thread
//   MapFile.*    (map_file.test, test_ros_map_file.cpp) ~save_map / ~load_map / ~localization_only
//   TimeJump.*, Loop.* (time_jump.test, loop.test; test_ros_time_jump.cpp) one map across time jumps
//   ImuCheck.*   (imu_check.test, test_ros_frames.cpp) the camera -> IMU rotation against the gyroscope
//   Live.*       (live.test, test_ros_live.cpp) a bag as a live camera into the pipelined tracker
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <map>
#include <memory>
#include <sstream>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <gtest/gtest.h>
#include <nodelet/loader.h>
#include <ros/ros.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <rosgraph_msgs/Log.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/PointCloud2.h>
#include <std_srvs/SetBool.h>
#include <std_srvs/Trigger.h>
#include <tf2_msgs/TFMessage.h>
#include <visualization_msgs/MarkerArray.h>

#include "ros_test_helpers.h"
#include "vitamin_e/SaveFile.h"
#include "vitamin_e/TrackingStatus.h"
#include "vitamin_e/eval/metrics.h"
#include "vitamin_e/eval/trajectory.h"
#include "vitamin_e/map/map_file.h"

using vitamin_e_test::Watcher;
using Statuses = std::vector<vitamin_e::TrackingStatus::ConstPtr>;

namespace {

std::string param(const std::string& name, const std::string& fallback = "") {
  std::string value;
  ros::NodeHandle("~").param(name, value, fallback);
  return value;
}

bool hasTriangles(const std::vector<visualization_msgs::MarkerArray::ConstPtr>& arrays) {
  for (const auto& a : arrays) {
    for (const auto& m : a->markers) {
      if (m.type == visualization_msgs::Marker::TRIANGLE_LIST && m.action == visualization_msgs::Marker::ADD &&
          m.points.size() >= 3 && m.points.size() % 3 == 0) {
        return true;
      }
    }
  }
  return false;
}

void resumePlayer() {
  ASSERT_TRUE(ros::service::waitForService("/player/pause_playback", ros::Duration(30.0)));
  std_srvs::SetBool resume;
  resume.request.data = false;
  ASSERT_TRUE(ros::service::call("/player/pause_playback", resume));
}

std::size_t framesProcessed(const Statuses& s) { return s.empty() ? 0 : s.back()->frames_processed; }

// The bag of pipeline.test played into the nodelets, once per process, by
// whichever Pipeline test runs first: each test sees the whole run, and none
// depends on another having run before it (--gtest_filter, shuffling).
struct BagRun {
  explicit BagRun(ros::NodeHandle& nh)
      : tf(nh, "/tf", 1000),
        points(nh, "/tracking/points"),
        mesh(nh, "/tsdf_meshing/mesh"),
        status(nh, "/tracking/status", 1000) {}
  Watcher<tf2_msgs::TFMessage> tf;
  Watcher<sensor_msgs::PointCloud2> points;
  Watcher<visualization_msgs::MarkerArray> mesh;
  Watcher<vitamin_e::TrackingStatus> status;
};

void playBagOnce(BagRun** out) {
  static BagRun* run = nullptr;  // never deleted: its subscribers must outlive the tests, not ros::shutdown
  static bool failed = false;
  ASSERT_FALSE(failed) << "the bag run failed in an earlier test";
  if (run) {
    *out = run;
    return;
  }
  failed = true;
  ros::NodeHandle nh;
  const int frames = std::stoi(param("frames", "60"));
  run = new BagRun(nh);
  ASSERT_TRUE(ros::service::waitForService("/tracking/save_trajectory", ros::Duration(30.0)));
  ASSERT_TRUE(run->status.waitForPublisher(30.0));
  ASSERT_TRUE(run->points.waitForPublisher(30.0));
  ASSERT_TRUE(run->mesh.waitForPublisher(30.0));
  resumePlayer();
  // Every frame of the bag is processed (~process_all_frames), however slow the SLAM.
  ASSERT_TRUE(
      run->status.waitFor([&](const Statuses& s) { return static_cast<int>(framesProcessed(s)) >= frames; }, 150.0))
      << "frames processed: " << framesProcessed(run->status.messages()) << " of " << frames;
  failed = false;
  *out = run;
}

}  // namespace

// (a) The bag played into the nodelets of one manager: tf, points and mesh arrive.
TEST(Pipeline, BagIntoNodelets) {
  BagRun* run = nullptr;
  ASSERT_NO_FATAL_FAILURE(playBagOnce(&run));
  const auto s = run->status.messages();
  ASSERT_FALSE(s.empty());
  std::size_t tracked = 0;  // the most of any status (SavedTrajectoryAte may have reset the tracker since)
  for (const auto& m : s) tracked = std::max<std::size_t>(tracked, m->frames_tracked);
  EXPECT_GT(tracked, 0u) << "last status: " << s.back()->state_name << " " << s.back()->message;

  EXPECT_TRUE(run->tf.waitFor(
      [](const auto& msgs) {
        for (const auto& m : msgs)
          for (const auto& t : m->transforms)
            if (t.header.frame_id == "map" && t.child_frame_id == "cam0") return true;
        return false;
      },
      10.0))
      << "no map -> cam0 on /tf";
  EXPECT_TRUE(run->points.waitFor(
      [](const auto& msgs) {
        for (const auto& m : msgs)
          if (m->width * m->height > 0 && m->header.frame_id == "map") return true;
        return false;
      },
      10.0))
      << "no non-empty cloud on /tracking/points";
  EXPECT_TRUE(run->mesh.waitFor(hasTriangles, 20.0)) << "no TRIANGLE_LIST marker on /tsdf_meshing/mesh";
}

// The trajectory saved through the service is close to the ground truth (after
// Sim(3) alignment), with the bounds of the offline test on the same kind of
// render (test_system_synthetic: ATE RMSE < 1 cm, >= 80 % of the frames). The
// map and the mesh can be saved too.
TEST(Pipeline, SavedTrajectoryAte) {
  BagRun* run = nullptr;
  ASSERT_NO_FATAL_FAILURE(playBagOnce(&run));
  const std::string out = param("output_dir", "/tmp");
  vitamin_e::SaveFile save;
  save.request.path = out + "/pipeline_trajectory.txt";
  ASSERT_TRUE(ros::service::call("/tracking/save_trajectory", save));
  ASSERT_TRUE(save.response.success) << save.response.message;
  save.request.path = out + "/pipeline_points.ply";
  ASSERT_TRUE(ros::service::call("/tracking/export_points", save));
  EXPECT_TRUE(save.response.success) << save.response.message;
  save.request.path = out + "/pipeline_map.vemap";
  ASSERT_TRUE(ros::service::call("/tracking/save_map", save));
  EXPECT_TRUE(save.response.success) << save.response.message;
  EXPECT_NO_THROW(vitamin_e::map::loadMapFile(save.request.path));
  save.request.path = out + "/pipeline_mesh.ply";
  ASSERT_TRUE(ros::service::call("/tsdf_meshing/save_mesh", save));
  EXPECT_TRUE(save.response.success) << save.response.message;

  namespace eval = vitamin_e::eval;
  const eval::Trajectory estimate = eval::readTum(out + "/pipeline_trajectory.txt");
  const eval::Trajectory truth = eval::readTum(param("data_dir") + "/groundtruth.tum");
  eval::EvalConfig config;
  config.frames = truth.size();
  eval::EvalResult result;
  ASSERT_NO_THROW(result = eval::evaluate(estimate, truth, config)) << estimate.size() << " poses saved";
  ROS_INFO_STREAM("saved trajectory vs ground truth:\n" << eval::summary(result, config));
  RecordProperty("ate_rmse_m", std::to_string(result.ate.rmse));
  RecordProperty("success_rate", std::to_string(result.success_rate));
  EXPECT_LT(result.ate.rmse, std::stod(param("max_ate_m", "0.01")));
  EXPECT_GE(result.success_rate, std::stod(param("min_success_rate", "0.8")));

  std_srvs::Trigger reset;
  ASSERT_TRUE(ros::service::call("/tracking/reset", reset));
  EXPECT_TRUE(reset.response.success) << reset.response.message;
}

// (b) Tracking and meshing in two processes: the per-frame messages cross a
// process boundary and a mesh still comes out.
TEST(TwoProcess, MeshArrives) {
  ros::NodeHandle nh;
  Watcher<visualization_msgs::MarkerArray> mesh(nh, "/tsdf_meshing/mesh");
  Watcher<vitamin_e::TrackingStatus> status(nh, "/tracking/status", 1000);
  ASSERT_TRUE(status.waitForPublisher(30.0));
  ASSERT_TRUE(mesh.waitForPublisher(30.0));
  resumePlayer();
  EXPECT_TRUE(mesh.waitFor(hasTriangles, 150.0))
      << "no TRIANGLE_LIST marker; frames processed " << framesProcessed(status.messages());
}

// (c) Bad input is reported on the log and does not stop the nodelet.
class BadInput : public ::testing::Test {
 protected:
  void SetUp() override {
    image_pub_ = nh_.advertise<sensor_msgs::Image>("/camera/image_raw", 10);
    info_pub_ = nh_.advertise<sensor_msgs::CameraInfo>("/camera/camera_info", 1, true);
    sensor_msgs::CameraInfo info;
    info.width = 160;
    info.height = 120;
    info.distortion_model = "plumb_bob";
    info.D = {0.0, 0.0, 0.0, 0.0, 0.0};
    info.K = {150.0, 0.0, 79.5, 0.0, 150.0, 59.5, 0.0, 0.0, 1.0};
    info_pub_.publish(info);
  }
  sensor_msgs::Image image(double t, const std::string& encoding, int w, int h, int channels) {
    sensor_msgs::Image img;
    img.header.stamp = ros::Time(t);
    img.header.frame_id = "camera";
    img.encoding = encoding;
    img.width = w;
    img.height = h;
    img.step = w * channels;
    img.data.resize(std::size_t{img.step} * h);
    for (std::size_t i = 0; i < img.data.size(); ++i) img.data[i] = static_cast<uint8_t>((i * 7919) >> 3);
    return img;
  }
  ros::NodeHandle nh_;
  ros::Publisher image_pub_, info_pub_;
};

TEST_F(BadInput, ErrorsLoggedNoCrash) {
  Watcher<vitamin_e::TrackingStatus> status(nh_, "/tracking/status", 1000);
  Watcher<rosgraph_msgs::Log> rosout(nh_, "/rosout", 1000);
  ASSERT_TRUE(status.waitForPublisher(30.0));
  ASSERT_TRUE(rosout.waitForAllPublishers(30.0));
  // The tracker subscribes to the image once it runs: wait for it.
  const auto deadline = ros::WallTime::now() + ros::WallDuration(30.0);
  while (image_pub_.getNumSubscribers() == 0 && ros::WallTime::now() < deadline) {
    ros::WallDuration(0.02).sleep();  // no event for a new subscriber: poll
  }
  ASSERT_GT(image_pub_.getNumSubscribers(), 0u);
  auto processed = [&](std::size_t n) {
    return status.waitFor([n](const Statuses& s) { return framesProcessed(s) >= n; }, 20.0);
  };

  // A valid frame, once the camera_info has been taken (retry: the info may come second).
  bool first = false;
  for (int attempt = 0; attempt < 50 && !first; ++attempt) {
    image_pub_.publish(image(1.0 + 0.001 * attempt, "mono8", 160, 120, 1));
    first = status.waitFor([](const Statuses& s) { return !s.empty(); }, 0.2);
  }
  ASSERT_TRUE(first) << "the tracker never processed a valid frame";
  const std::size_t n0 = framesProcessed(status.messages());

  image_pub_.publish(image(2.0, "rgb8", 160, 120, 3));  // converted, processed
  EXPECT_TRUE(processed(n0 + 1)) << "rgb8 frame not processed";

  image_pub_.publish(image(3.0, "32FC1", 160, 120, 4));
  EXPECT_TRUE(vitamin_e_test::waitForLogError(rosout, "unsupported image encoding", 10.0));

  image_pub_.publish(image(4.0, "rgb8", 200, 100, 3));
  EXPECT_TRUE(vitamin_e_test::waitForLogError(rosout, "image dropped: size 200x100", 10.0));

  image_pub_.publish(image(1.5, "mono8", 160, 120, 1));
  EXPECT_TRUE(vitamin_e_test::waitForLogError(rosout, "does not increase", 10.0));

  image_pub_.publish(image(5.0, "mono8", 160, 120, 1));  // still alive, still processing
  EXPECT_TRUE(processed(n0 + 2)) << "the tracker stopped processing after bad input";
}

// (c) The rest of the encoding matrix (bgr8 and mono16 converted, bayer
// rejected by name), a repeated stamp, and a stamp of wall-clock size after
// bag-sized ones: only the order of stamps matters.
TEST_F(BadInput, MoreEncodingsAndStamps) {
  Watcher<vitamin_e::TrackingStatus> status(nh_, "/tracking/status", 1000);
  Watcher<rosgraph_msgs::Log> rosout(nh_, "/rosout", 1000);
  ASSERT_TRUE(status.waitForPublisher(30.0));
  ASSERT_TRUE(rosout.waitForAllPublishers(30.0));
  const auto deadline = ros::WallTime::now() + ros::WallDuration(30.0);
  while (image_pub_.getNumSubscribers() == 0 && ros::WallTime::now() < deadline) ros::WallDuration(0.02).sleep();
  ASSERT_GT(image_pub_.getNumSubscribers(), 0u);
  auto processed = [&](std::size_t n) {
    return status.waitFor([n](const Statuses& s) { return framesProcessed(s) >= n; }, 20.0);
  };
  bool first = false;
  for (int attempt = 0; attempt < 50 && !first; ++attempt) {
    image_pub_.publish(image(20.0 + 0.001 * attempt, "mono8", 160, 120, 1));
    first = status.waitFor([](const Statuses& s) { return !s.empty(); }, 0.2);
  }
  ASSERT_TRUE(first) << "the tracker never processed a valid frame";
  const std::size_t n0 = framesProcessed(status.messages());

  image_pub_.publish(image(21.0, "bgr8", 160, 120, 3));
  EXPECT_TRUE(processed(n0 + 1)) << "bgr8 frame not processed";
  image_pub_.publish(image(22.0, "mono16", 160, 120, 2));
  EXPECT_TRUE(processed(n0 + 2)) << "mono16 frame not processed";

  // The errors are throttled per call site (2 s) and the previous test logged
  // them too: the bad frame is sent again until its error is logged.
  auto publish_until_logged = [&](const sensor_msgs::Image& img, const std::string& error) {
    const auto deadline = ros::WallTime::now() + ros::WallDuration(10.0);
    do {
      image_pub_.publish(img);
      if (vitamin_e_test::waitForLogError(rosout, error, 0.25)) return true;
    } while (ros::WallTime::now() < deadline);
    return false;
  };
  EXPECT_TRUE(
      publish_until_logged(image(23.0, "bayer_rggb8", 160, 120, 1), "unsupported image encoding 'bayer_rggb8'"));
  // The same stamp as the mono16 frame.
  EXPECT_TRUE(publish_until_logged(image(22.0, "mono8", 160, 120, 1), "does not increase"));

  image_pub_.publish(image(1.8e9, "mono8", 160, 120, 1));  // wall-clock-sized stamp
  EXPECT_TRUE(processed(n0 + 3)) << "a frame with a wall-clock stamp after bag stamps was not processed";
  for (const auto& s : status.messages()) {
    EXPECT_TRUE(std::isfinite(s->ms_per_frame));
    EXPECT_LE(s->frames_tracked, s->frames_processed);
  }
}

// (c) ~reset clears the last stamp (and the path): a frame older than the
// last one is processed after it, in a new segment. A stamp jumping back by more than
// ~time_jump_threshold (1 s) restarts the SLAM by itself; a small step back is still dropped.
TEST_F(BadInput, ResetAndTimeJumpsStartNewSegments) {
  Watcher<vitamin_e::TrackingStatus> status(nh_, "/tracking/status", 1000);
  ASSERT_TRUE(status.waitForPublisher(30.0));
  const auto deadline = ros::WallTime::now() + ros::WallDuration(30.0);
  while (image_pub_.getNumSubscribers() == 0 && ros::WallTime::now() < deadline) ros::WallDuration(0.02).sleep();
  ASSERT_GT(image_pub_.getNumSubscribers(), 0u);
  // The status of the frame stamped t (each frame's status carries its image's stamp).
  auto status_of = [&](double t) -> vitamin_e::TrackingStatus::ConstPtr {
    vitamin_e::TrackingStatus::ConstPtr found;
    status.waitFor(
        [&](const Statuses& s) {
          for (const auto& m : s)
            if (std::abs(m->header.stamp.toSec() - t) < 1e-3) found = m;
          return found != nullptr;
        },
        20.0);
    return found;
  };
  const double t0 = 1.9e9;  // after every stamp of the other BadInput tests
  bool first = false;
  for (int attempt = 0; attempt < 50 && !first; ++attempt) {
    image_pub_.publish(image(t0 + 0.001 * attempt, "mono8", 160, 120, 1));
    first = status.waitFor([](const Statuses& s) { return !s.empty(); }, 0.2);
  }
  ASSERT_TRUE(first);
  image_pub_.publish(image(t0 + 10.0, "mono8", 160, 120, 1));
  const auto before = status_of(t0 + 10.0);
  ASSERT_TRUE(before);

  std_srvs::Trigger reset;
  ASSERT_TRUE(ros::service::call("/tracking/reset", reset));
  EXPECT_TRUE(reset.response.success) << reset.response.message;
  image_pub_.publish(image(t0 + 9.5, "mono8", 160, 120, 1));  // 0.5 s before the last frame
  const auto after_reset = status_of(t0 + 9.5);
  ASSERT_TRUE(after_reset) << "after ~reset, a frame older than the last was not processed";
  EXPECT_EQ(after_reset->segment, before->segment + 1);
  EXPECT_EQ(after_reset->frames_processed, before->frames_processed + 1) << "counts go on over segments";

  image_pub_.publish(image(t0 + 9.2, "mono8", 160, 120, 1));  // 0.3 s back: dropped
  image_pub_.publish(image(t0 + 2.0, "mono8", 160, 120, 1));  // 7.5 s back: a new SLAM run
  const auto after_jump = status_of(t0 + 2.0);
  ASSERT_TRUE(after_jump) << "a frame after a jump back in time was not processed";
  EXPECT_EQ(after_jump->segment, before->segment + 2);
  EXPECT_EQ(after_jump->frames_processed, after_reset->frames_processed + 1) << "the 0.3 s step back was processed";
  for (const auto& m : status.messages()) EXPECT_GT(std::abs(m->header.stamp.toSec() - (t0 + 9.2)), 1e-3);
}

// A camera_info that changes after the calibration was taken (a driver reloading its
// calibration file): the tracker keeps the first and says so, once.
TEST_F(BadInput, CameraInfoChangeWarnedOnce) {
  Watcher<vitamin_e::TrackingStatus> status(nh_, "/tracking/status", 1000);
  Watcher<rosgraph_msgs::Log> rosout(nh_, "/rosout", 1000);
  ASSERT_TRUE(status.waitForPublisher(30.0));
  // The warning is said once: the manager's /rosout must be connected before it is.
  ASSERT_TRUE(rosout.waitForAllPublishers(30.0));
  const auto deadline = ros::WallTime::now() + ros::WallDuration(30.0);
  while (image_pub_.getNumSubscribers() == 0 && ros::WallTime::now() < deadline) ros::WallDuration(0.02).sleep();
  ASSERT_GT(image_pub_.getNumSubscribers(), 0u);
  bool first = false;
  for (int attempt = 0; attempt < 50 && !first; ++attempt) {
    image_pub_.publish(image(2.0e9 + 0.001 * attempt, "mono8", 160, 120, 1));
    first = status.waitFor([](const Statuses& s) { return !s.empty(); }, 0.2);
  }
  ASSERT_TRUE(first) << "the tracker never processed a valid frame";
  sensor_msgs::CameraInfo info;
  info.width = 160;
  info.height = 120;
  info.distortion_model = "plumb_bob";
  info.D = {0.0, 0.0, 0.0, 0.0, 0.0};
  info.K = {165.0, 0.0, 79.5, 0.0, 165.0, 59.5, 0.0, 0.0, 1.0};  // fx, fy + 10 %
  info_pub_.publish(info);
  EXPECT_TRUE(vitamin_e_test::waitForLog(rosout, rosgraph_msgs::Log::WARN, {"camera_info changed"}, 10.0))
      << "a changed camera_info was ignored silently";
  // Once: the same change again is not said again.
  const auto count = [&] {
    int n = 0;
    for (const auto& l : rosout.messages()) n += l->msg.find("camera_info changed") != std::string::npos ? 1 : 0;
    return n;
  };
  info_pub_.publish(info);
  image_pub_.publish(image(2.1e9, "mono8", 160, 120, 1));
  EXPECT_TRUE(status.waitFor([](const Statuses& s) { return s.back()->header.stamp.toSec() > 2.05e9; }, 10.0));
  EXPECT_EQ(count(), 1);
}

// (d) ~trajectory_file and ~map_file (the PLY export, now also
// ~export_points) are written when the tracking
// nodelet goes away, as on SIGINT of its manager: loaded in this process with a
// nodelet::Loader, fed the test bag's images, then unloaded.
TEST(ShutdownSave, TrajectoryAndMapWrittenOnUnload) {
  const std::string out = param("output_dir", "/tmp");
  const std::string traj_path = out + "/shutdown_trajectory.txt";
  const std::string map_path = out + "/shutdown_map.ply";
  std::remove(traj_path.c_str());
  std::remove(map_path.c_str());
  ros::NodeHandle nh;
  ros::param::set("/saver/trajectory_file", traj_path);
  ros::param::set("/saver/map_file", map_path);
  ros::param::set("/saver/calibration_file", param("data_dir") + "/calibration.yaml");
  ros::param::set("/saver/process_all_frames", true);

  std::vector<sensor_msgs::Image::ConstPtr> images;
  {
    rosbag::Bag bag(param("data_dir") + "/sequence.bag");
    for (const rosbag::MessageInstance& m : rosbag::View(bag)) {
      if (auto img = m.instantiate<sensor_msgs::Image>()) images.push_back(img);
    }
  }
  ASSERT_GE(images.size(), 20u);
  ros::Publisher pub = nh.advertise<sensor_msgs::Image>("/saver_image", 100);
  Watcher<vitamin_e::TrackingStatus> status(nh, "/saver/status", 1000);
  {
    nodelet::Loader loader(false);
    ros::M_string remap;
    remap[ros::names::resolve("/saver/image")] = "/saver_image";
    remap["/image"] = "/saver_image";
    ASSERT_TRUE(loader.load("/saver", "vitamin_e/TrackingNodelet", remap, nodelet::V_string()));
    const auto deadline = ros::WallTime::now() + ros::WallDuration(30.0);
    while (pub.getNumSubscribers() == 0 && ros::WallTime::now() < deadline) ros::WallDuration(0.02).sleep();
    ASSERT_GT(pub.getNumSubscribers(), 0u) << "the nodelet did not subscribe to /saver_image";
    for (const auto& img : images) {
      pub.publish(img);
      ros::WallDuration(0.005).sleep();
    }
    EXPECT_TRUE(status.waitFor([&](const Statuses& s) { return framesProcessed(s) >= images.size(); }, 60.0))
        << "frames processed: " << framesProcessed(status.messages()) << " of " << images.size();
    // Unloading a nodelet while one of its callbacks runs makes nodelet::Loader delete it after
    // its callback queues (roscpp then crashes removing the publishers' callbacks). Frames are
    // not processed on those queues (the SLAM has its own thread), but a service call served
    // on the nodelet's queue makes sure nothing else (a connection callback) is running there.
    vitamin_e::SaveFile idle;
    idle.request.path = out + "/shutdown_trajectory_before_unload.txt";
    ASSERT_TRUE(ros::service::call("/saver/save_trajectory", idle));
    ASSERT_TRUE(loader.unload("/saver"));
  }
  // trajectory.txt: a header and finite TUM lines; points.ply: a complete header.
  std::ifstream traj(traj_path);
  ASSERT_TRUE(traj.good()) << traj_path << " not written on unload";
  std::string line;
  int poses = 0;
  while (std::getline(traj, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream ls(line);
    double v[8];
    int k = 0;
    while (k < 8 && ls >> v[k]) ++k;
    ASSERT_EQ(k, 8) << line;
    for (double x : v) EXPECT_TRUE(std::isfinite(x)) << line;
    ++poses;
  }
  const auto s = status.messages();
  ASSERT_FALSE(s.empty());
  EXPECT_EQ(poses, static_cast<int>(s.back()->frames_tracked)) << "saved poses vs frames tracked";
  EXPECT_GT(poses, 0) << "no pose tracked on the test bag";
  std::ifstream ply(map_path, std::ios::binary);
  ASSERT_TRUE(ply.good()) << map_path << " not written on unload";
  std::string ply_text((std::istreambuf_iterator<char>(ply)), std::istreambuf_iterator<char>());
  EXPECT_EQ(ply_text.rfind("ply\n", 0), 0u);
  EXPECT_NE(ply_text.find("end_header\n"), std::string::npos);
}

// (d) Unloading while the SLAM thread holds a frame (~debug_frame_delay 30 s),
// its queue is full and the image callback waits on it: the nodelet stops its threads in order
// (queue closed, callback woken, subscription shut down, SLAM thread joined) and saves, without
// waiting for the held or the queued frames. Three rounds (an unload crash was intermittent).
TEST(ShutdownSave, UnloadWhileFramesWait) {
  const std::string out = param("output_dir", "/tmp");
  std::vector<sensor_msgs::Image::ConstPtr> images;
  {
    rosbag::Bag bag(param("data_dir") + "/sequence.bag");
    for (const rosbag::MessageInstance& m : rosbag::View(bag)) {
      if (auto img = m.instantiate<sensor_msgs::Image>()) images.push_back(img);
      if (images.size() == 10) break;
    }
  }
  ASSERT_EQ(images.size(), 10u);
  ros::NodeHandle nh;
  ros::param::set("/busy/calibration_file", param("data_dir") + "/calibration.yaml");
  ros::param::set("/busy/process_all_frames", true);
  ros::param::set("/busy/debug_frame_delay", 30.0);
  ros::param::set("/busy/diagnostic_period", 0.1);
  for (int round = 0; round < 3; ++round) {
    // A topic per round: the previous round's subscriber may still be counted for a while.
    const std::string topic = "/busy_image_" + std::to_string(round);
    ros::Publisher pub = nh.advertise<sensor_msgs::Image>(topic, 100);
    const std::string traj_path = out + "/busy_trajectory_" + std::to_string(round) + ".txt";
    std::remove(traj_path.c_str());
    ros::param::set("/busy/trajectory_file", traj_path);
    Watcher<diagnostic_msgs::DiagnosticArray> diagnostics(nh, "/diagnostics", 1000);
    std::chrono::steady_clock::time_point t0;
    {
      nodelet::Loader loader(false);
      ros::M_string remap;
      remap[ros::names::resolve("/busy/image")] = topic;
      remap["/image"] = topic;
      ASSERT_TRUE(loader.load("/busy", "vitamin_e/TrackingNodelet", remap, nodelet::V_string()));
      const auto deadline = ros::WallTime::now() + ros::WallDuration(30.0);
      while (pub.getNumSubscribers() == 0 && ros::WallTime::now() < deadline) ros::WallDuration(0.02).sleep();
      ASSERT_GT(pub.getNumSubscribers(), 0u) << "round " << round;
      for (const auto& img : images) pub.publish(img);
      // One frame held, the queue full (4 waiting): the callback with the sixth frame waits.
      const bool full = diagnostics.waitFor(
          [](const std::vector<diagnostic_msgs::DiagnosticArray::ConstPtr>& arrays) {
            for (const auto& a : arrays)
              for (const auto& s : a->status) {
                if (s.name.find("busy: vitamin_e tracking") == std::string::npos) continue;
                std::map<std::string, std::string> kv;
                for (const auto& v : s.values) kv[v.key] = v.value;
                if (kv["frames queued"] == kv["queue capacity"] && kv["SLAM thread busy"] == "yes") return true;
              }
            return false;
          },
          30.0);
      EXPECT_TRUE(full) << "round " << round << ": the queue never filled";
      vitamin_e::SaveFile idle;  // nothing else running on the nodelet's queue (see above)
      idle.request.path = out + "/busy_trajectory_before_unload.txt";
      ASSERT_TRUE(ros::service::call("/busy/save_trajectory", idle));
      t0 = std::chrono::steady_clock::now();
      ASSERT_TRUE(loader.unload("/busy"));
    }
    // The loader is gone: had a callback of the nodelet been running at unload (a service
    // call's end), the nodelet was deleted after it, before the loader's threads ended.
    const double unload_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    EXPECT_LT(unload_s, 10.0) << "round " << round << ": the unload waited for the held frame (30 s)";
    std::ifstream traj(traj_path);
    EXPECT_TRUE(traj.good()) << traj_path << " not written on unload";
  }
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_ros_nodelets");
  ros::AsyncSpinner spinner(2);
  spinner.start();
  const int result = RUN_ALL_TESTS();
  spinner.stop();
  ros::shutdown();
  return result;
}
