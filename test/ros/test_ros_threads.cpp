// Threads.* (threads.test): the SLAM runs on its own thread fed by a bounded
// queue. The trackers hold every frame ~debug_frame_delay (D) seconds before processing it, so
// after the status of frame k, frame k+1 is in progress for at least D and the later ones wait.
// What a service saw tells whether it waited, no clock is read: a ~save_trajectory file holds
// the poses of the frames done when it was written, and its answer counts the frames not
// processed yet:
//  - bag mode: ~save_trajectory and dynamic_reconfigure answer while frame k+1 is in progress
//    (the file has frame k's poses, not k+1's), each saved trajectory is a prefix of the final
//    one, ~save_map waits for the frame in progress only (frames still wait after it), and
//    /diagnostics shows the queued frames;
//  - live mode: a burst of frames while one is in progress: only the newest is processed next,
//    and every frame seen and not processed is counted as dropped by the queue;
//  - ~reset while frames wait (bag mode): it runs after the frame in progress, the waiting
//    frames are all processed, in the new segment, none is lost.
#include <fstream>
#include <map>
#include <regex>
#include <string>
#include <vector>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <dynamic_reconfigure/Reconfigure.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/Image.h>
#include <std_srvs/Trigger.h>

#include "ros_test_helpers.h"
#include "vitamin_e/SaveFile.h"
#include "vitamin_e/TrackingStatus.h"

using vitamin_e_test::privateParam;
using vitamin_e_test::Watcher;
using Statuses = std::vector<vitamin_e::TrackingStatus::ConstPtr>;
using Diagnostics = std::vector<diagnostic_msgs::DiagnosticArray::ConstPtr>;

namespace {

// n images of the test bag, every `stride`-th.
std::vector<sensor_msgs::Image::ConstPtr> bagImages(std::size_t n, std::size_t stride = 1) {
  std::vector<sensor_msgs::Image::ConstPtr> images;
  rosbag::Bag bag(privateParam("data_dir") + "/sequence.bag");
  std::size_t i = 0;
  for (const rosbag::MessageInstance& m : rosbag::View(bag)) {
    auto img = m.instantiate<sensor_msgs::Image>();
    if (img && i++ % stride == 0) images.push_back(img);
    if (images.size() == n) break;
  }
  return images;
}

bool waitForSubscriber(const ros::Publisher& pub, double timeout_s) {
  const auto deadline = ros::WallTime::now() + ros::WallDuration(timeout_s);
  while (pub.getNumSubscribers() == 0) {
    if (ros::WallTime::now() > deadline) return false;
    ros::WallDuration(0.02).sleep();  // no event for a new subscriber: poll
  }
  return true;
}

// The pose lines of a TUM file (the '#' lines skipped).
std::vector<std::string> poseLines(const std::string& path) {
  std::vector<std::string> lines;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    if (!line.empty() && line[0] != '#') lines.push_back(line);
  }
  return lines;
}

// "...; N frame(s) not processed yet" in a ~save_trajectory answer: N, or 0.
int notProcessed(const std::string& message) {
  std::smatch m;
  static const std::regex re("(\\d+) frame\\(s\\) not processed yet");
  return std::regex_search(message, m, re) ? std::stoi(m[1]) : 0;
}

// The key/values of the newest /diagnostics status of tracker `name` satisfying pred.
bool waitForDiagnostic(Watcher<diagnostic_msgs::DiagnosticArray>& diagnostics, const std::string& name,
                       const std::function<bool(std::map<std::string, std::string>&)>& pred, double timeout_s,
                       std::map<std::string, std::string>* found) {
  return diagnostics.waitFor(
      [&](const Diagnostics& arrays) {
        for (const auto& a : arrays) {
          for (const auto& s : a->status) {
            if (s.name.find(name + ": vitamin_e tracking") == std::string::npos) continue;
            std::map<std::string, std::string> kv;
            for (const auto& v : s.values) kv[v.key] = v.value;
            if (pred(kv)) {
              *found = kv;
              return true;
            }
          }
        }
        return false;
      },
      timeout_s);
}

}  // namespace

TEST(Threads, ServicesAndReconfigureDoNotWaitForTheFrameInProgress) {
  const double D = std::stod(privateParam("frame_delay", "2.0"));
  const std::string out = privateParam("output_dir", "/tmp");
  // Every third frame: the test bag initializes at its frame 9 (parallax), so the later
  // snapshots hold poses.
  constexpr std::size_t kFrames = 7;
  const auto images = bagImages(kFrames, 3);
  ASSERT_EQ(images.size(), kFrames);

  ros::NodeHandle nh;
  ros::Publisher pub = nh.advertise<sensor_msgs::Image>("/slow_bag_image", 100);
  Watcher<vitamin_e::TrackingStatus> status(nh, "/slow_bag/status", 1000);
  Watcher<diagnostic_msgs::DiagnosticArray> diagnostics(nh, "/diagnostics", 1000);
  for (const char* name : {"/slow_bag/save_trajectory", "/slow_bag/save_map", "/slow_bag/set_parameters"}) {
    ASSERT_TRUE(ros::service::waitForService(name, ros::Duration(30.0))) << name;
  }
  // Persistent connections (made once the services exist): a call is one exchange on an open
  // socket, no lookup.
  ros::ServiceClient save = nh.serviceClient<vitamin_e::SaveFile>("/slow_bag/save_trajectory", true);
  ros::ServiceClient save_map = nh.serviceClient<vitamin_e::SaveFile>("/slow_bag/save_map", true);
  ros::ServiceClient reconfigure = nh.serviceClient<dynamic_reconfigure::Reconfigure>("/slow_bag/set_parameters", true);
  ASSERT_TRUE(status.waitForPublisher(30.0));
  ASSERT_TRUE(waitForSubscriber(pub, 30.0));
  for (const auto& img : images) pub.publish(img);

  std::vector<std::vector<std::string>> snapshots;
  std::vector<std::size_t> snapshot_status;  // the statuses received when each snapshot was asked for
  for (std::size_t k = 1; k < kFrames; ++k) {
    // After the status of frame k, frame k + 1 is in progress for at least D.
    ASSERT_TRUE(status.waitForCount(k, 30.0 + 2.0 * D)) << "statuses: " << status.messages().size();
    if (k == 4) {
      // dynamic_reconfigure first, once frames have poses: the snapshot after it shows that
      // frame 5 was still in progress.
      dynamic_reconfigure::Reconfigure r;
      dynamic_reconfigure::DoubleParameter period;
      period.name = "map_points_period";
      period.value = 3.0;
      r.request.config.doubles.push_back(period);
      ASSERT_TRUE(reconfigure.call(r));
    }
    vitamin_e::SaveFile srv;
    srv.request.path = out + "/threads_trajectory_" + std::to_string(k) + ".txt";
    ASSERT_TRUE(save.call(srv));
    ASSERT_TRUE(srv.response.success) << srv.response.message;
    if (k + 2 <= kFrames) {
      // Frame k + 1 in progress and k + 2 waiting: neither can be done within 2 D of status k.
      EXPECT_GE(notProcessed(srv.response.message), 1) << srv.response.message;
    }
    snapshots.push_back(poseLines(srv.request.path));
    snapshot_status.push_back(k);

    if (k == 2) {
      // The map is the SLAM thread's: ~save_map runs between two frames, ahead of the waiting
      // ones. Frame 3 in progress, 4 to 7 waiting: it waits for frame 3 only, so right after it
      // frame 4 is in progress (or about to be) and 5 to 7 wait; had it waited for the queue,
      // none would.
      vitamin_e::SaveFile m;
      m.request.path = out + "/threads_map.vemap";
      ASSERT_TRUE(save_map.call(m));
      EXPECT_TRUE(m.response.success) << m.response.message;
      vitamin_e::SaveFile after;
      after.request.path = out + "/threads_trajectory_after_map.txt";
      ASSERT_TRUE(save.call(after));
      EXPECT_GE(notProcessed(after.response.message), 4)
          << "~save_map waited for more than the frame in progress: " << after.response.message;
    }
  }

  // The queue as /diagnostics shows it while frames wait (reported every 0.2 s).
  std::map<std::string, std::string> kv;
  EXPECT_TRUE(waitForDiagnostic(
      diagnostics, "slow_bag",
      [](auto& kv) { return kv.count("frames queued") && kv.count("frames dropped by the queue"); }, 10.0, &kv));

  ASSERT_TRUE(status.waitFor([&](const Statuses& s) { return s.size() >= kFrames; }, 30.0 + 2.0 * D));
  EXPECT_EQ(status.messages().back()->frames_processed, kFrames);
  vitamin_e::SaveFile last;
  last.request.path = out + "/threads_trajectory_final.txt";
  ASSERT_TRUE(save.call(last));
  ASSERT_TRUE(last.response.success) << last.response.message;
  EXPECT_EQ(notProcessed(last.response.message), 0) << last.response.message;
  const auto final_poses = poseLines(last.request.path);
  // Every snapshot is the trajectory as it was: a prefix of the final one (a pose never
  // changes after its frame).
  const auto statuses = status.messages();
  for (std::size_t i = 0; i < snapshots.size(); ++i) {
    ASSERT_LE(snapshots[i].size(), final_poses.size()) << "snapshot " << i + 1;
    // The poses of the frames done when it was asked for, no more (frame k's status counts
    // them): had the call, or dynamic_reconfigure before it, waited for frame k + 1 in
    // progress, its pose would be there too.
    EXPECT_EQ(snapshots[i].size(), statuses[snapshot_status[i] - 1]->frames_tracked) << "snapshot " << i + 1;
    for (std::size_t j = 0; j < snapshots[i].size(); ++j) {
      EXPECT_EQ(snapshots[i][j], final_poses[j]) << "snapshot " << i + 1 << ", pose " << j;
    }
    if (i > 0) {
      EXPECT_GE(snapshots[i].size(), snapshots[i - 1].size());
    }
  }
  EXPECT_GT(snapshots.back().size(), 0u) << "no pose in the snapshots: the prefix check checked nothing";
  // Bag mode drops nothing.
  EXPECT_TRUE(waitForDiagnostic(
      diagnostics, "slow_bag", [&](auto& kv) { return kv["frames processed"] == std::to_string(kFrames); }, 10.0, &kv));
  EXPECT_EQ(kv["frames dropped by the queue"], "0");
}

TEST(Threads, LiveQueueKeepsTheNewestFrame) {
  constexpr std::size_t kFrames = 6;
  const auto images = bagImages(kFrames);
  ASSERT_EQ(images.size(), kFrames);
  ros::NodeHandle nh;
  ros::Publisher pub = nh.advertise<sensor_msgs::Image>("/slow_live_image", 100);
  Watcher<vitamin_e::TrackingStatus> status(nh, "/slow_live/status", 1000);
  Watcher<diagnostic_msgs::DiagnosticArray> diagnostics(nh, "/diagnostics", 1000);
  ASSERT_TRUE(status.waitForPublisher(30.0));
  ASSERT_TRUE(waitForSubscriber(pub, 30.0));
  // A burst: the first frame taken is held D seconds, the others arrive meanwhile and each
  // replaces the one waiting.
  for (const auto& img : images) pub.publish(img);
  const ros::Time newest = images.back()->header.stamp;
  ASSERT_TRUE(status.waitFor(
      [&](const Statuses& s) {
        for (const auto& m : s)
          if (m->header.stamp == newest) return true;
        return false;
      },
      60.0))
      << "the newest frame was not processed";
  const auto s = status.messages();
  // The first frame the SLAM thread took (held D) and the newest; the rest dropped, by the
  // queue or already by the subscriber's queue of 1 (if the image thread was not scheduled).
  EXPECT_LE(s.size(), 2u) << "frames between the first one taken and the newest were processed";
  EXPECT_EQ(s.back()->header.stamp, newest);
  // Every frame the callback saw and the SLAM did not process was dropped by the queue.
  std::map<std::string, std::string> kv;
  ASSERT_TRUE(waitForDiagnostic(
      diagnostics, "slow_live",
      [&](auto& kv) { return kv["frames processed"] == std::to_string(s.size()) && kv["SLAM thread busy"] == "no"; },
      10.0, &kv));
  const int received = std::stoi(kv["frames received"]);
  EXPECT_EQ(std::stoi(kv["frames dropped by the queue"]), received - static_cast<int>(s.size()));
  EXPECT_EQ(kv["queue mode"], "newest frame only");
}

TEST(Threads, ResetWhileFramesWait) {
  const double D = std::stod(privateParam("frame_delay", "2.0"));
  const std::string out = privateParam("output_dir", "/tmp");
  constexpr std::size_t kFrames = 6;
  const auto images = bagImages(kFrames, 3);
  ASSERT_EQ(images.size(), kFrames);
  ros::NodeHandle nh;
  ros::Publisher pub = nh.advertise<sensor_msgs::Image>("/slow_reset_image", 100);
  Watcher<vitamin_e::TrackingStatus> status(nh, "/slow_reset/status", 1000);
  Watcher<diagnostic_msgs::DiagnosticArray> diagnostics(nh, "/diagnostics", 1000);
  ASSERT_TRUE(ros::service::waitForService("/slow_reset/reset", ros::Duration(30.0)));
  ASSERT_TRUE(ros::service::waitForService("/slow_reset/save_trajectory", ros::Duration(30.0)));
  ASSERT_TRUE(status.waitForPublisher(30.0));
  ASSERT_TRUE(waitForSubscriber(pub, 30.0));
  for (const auto& img : images) pub.publish(img);
  // Status of frame 1: frame 2 in progress (held D), frames 3..6 wait.
  ASSERT_TRUE(status.waitForCount(1, 30.0 + 2.0 * D));
  std_srvs::Trigger reset;
  ASSERT_TRUE(ros::service::call("/slow_reset/reset", reset));
  EXPECT_TRUE(reset.response.success) << reset.response.message;
  EXPECT_NE(reset.response.message.find("segment 2"), std::string::npos) << reset.response.message;
  // It waited for the frame in progress (2), not for the 4 waiting ones: frames still wait after
  // it, and the segments below show that it ran between frames 2 and 3.
  vitamin_e::SaveFile save;
  save.request.path = out + "/threads_reset_trajectory.txt";
  ASSERT_TRUE(ros::service::call("/slow_reset/save_trajectory", save));
  EXPECT_TRUE(save.response.success) << save.response.message;
  EXPECT_GE(notProcessed(save.response.message), 1) << save.response.message;

  // Every frame is processed: the one in progress in segment 1, the waiting ones in segment 2.
  ASSERT_TRUE(status.waitForCount(kFrames, 30.0 + 2.0 * kFrames * D)) << "statuses: " << status.messages().size();
  const auto s = status.messages();
  ASSERT_EQ(s.size(), kFrames);
  for (std::size_t i = 0; i < kFrames; ++i) {
    EXPECT_EQ(s[i]->header.stamp, images[i]->header.stamp) << "frame " << i + 1 << " out of order";
    EXPECT_EQ(s[i]->segment, i < 2 ? 1u : 2u) << "frame " << i + 1;
  }
  EXPECT_EQ(s.back()->frames_processed, kFrames);
  std::map<std::string, std::string> kv;
  ASSERT_TRUE(waitForDiagnostic(
      diagnostics, "slow_reset",
      [&](auto& kv) { return kv["frames processed"] == std::to_string(kFrames) && kv["SLAM thread busy"] == "no"; },
      10.0, &kv));
  EXPECT_EQ(kv["frames dropped by the queue"], "0");
  EXPECT_EQ(kv["frames received"], std::to_string(kFrames));
}
