// rostests of the ROS interface as robot builders expect it:
//   Interfaces.* (interfaces.test) one bag (sensors.bag: raw, compressed and rectified images,
//       camera_info) into four tracking nodelets: raw + camera_info (the reference),
//       ~image_transport compressed, image_rect (rectified camera_info), and raw with a tenth
//       of the tracked points (config few_points.yaml)
#include <algorithm>
#include <cmath>
#include <memory>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <gtest/gtest.h>
#include <nav_msgs/Odometry.h>
#include <nav_msgs/Path.h>
#include <ros/ros.h>
#include <std_srvs/SetBool.h>
#include <Eigen/Eigenvalues>

#include "ros_test_helpers.h"
#include "vitamin_e/SaveFile.h"
#include "vitamin_e/TrackingStatus.h"
#include "vitamin_e/eval/metrics.h"
#include "vitamin_e/pipeline/session.h"

using vitamin_e_test::Watcher;
using Statuses = std::vector<vitamin_e::TrackingStatus::ConstPtr>;
namespace eval = vitamin_e::eval;

namespace {

std::size_t processed(const Statuses& s) { return s.empty() ? 0 : s.back()->frames_processed; }

void setPaused(bool paused) {
  ASSERT_TRUE(ros::service::waitForService("/player/pause_playback", ros::Duration(30.0)));
  std_srvs::SetBool pause;
  pause.request.data = paused;
  ASSERT_TRUE(ros::service::call("/player/pause_playback", pause));
}

eval::Trajectory toEval(const vitamin_e::pipeline::TrajectorySegment& s) {
  eval::Trajectory t;
  for (const auto& e : s.poses) t.push_back({e.timestamp, e.T_w_c});
  return t;
}

// ATE RMSE of a saved trajectory's segment against the test sequence's ground truth.
double segmentAte(const vitamin_e::pipeline::TrajectorySegment& segment) {
  const eval::Trajectory truth = eval::readTum(vitamin_e_test::privateParam("data_dir") + "/groundtruth.tum");
  eval::EvalConfig config;
  config.frames = truth.size();
  const eval::EvalResult r = eval::evaluate(toEval(segment), truth, config);
  return r.ate.rmse;
}

// Saves a tracker's trajectory through its service; returns its segments.
std::vector<vitamin_e::pipeline::TrajectorySegment> saveTrajectory(const std::string& tracker) {
  vitamin_e::SaveFile save;
  save.request.path = vitamin_e_test::privateParam("output_dir", "/tmp") + "/" + tracker + "_trajectory.txt";
  EXPECT_TRUE(ros::service::call("/" + tracker + "/save_trajectory", save)) << tracker;
  EXPECT_TRUE(save.response.success) << save.response.message;
  return vitamin_e::pipeline::readSegmentsTum(save.request.path);
}

// The subscriptions of Interfaces.*: made before the bag plays, read by the later tests.
struct InterfaceRun {
  ros::NodeHandle nh;
  Watcher<vitamin_e::TrackingStatus> raw{nh, "/tracking/status", 1000};
  Watcher<vitamin_e::TrackingStatus> compressed{nh, "/tracking_compressed/status", 1000};
  Watcher<vitamin_e::TrackingStatus> rect{nh, "/tracking_rect/status", 1000};
  Watcher<vitamin_e::TrackingStatus> few{nh, "/tracking_few/status", 1000};
  Watcher<nav_msgs::Odometry> odom{nh, "/tracking/odometry", 1000};
  Watcher<nav_msgs::Odometry> odom_few{nh, "/tracking_few/odometry", 1000};
  Watcher<diagnostic_msgs::DiagnosticArray> diagnostics{nh, "/diagnostics", 1000};
};
std::unique_ptr<InterfaceRun> g_run;

double ateOf(const std::string& tracker) {
  const auto segments = saveTrajectory(tracker);
  EXPECT_EQ(segments.size(), 1u) << tracker;
  if (segments.empty()) return 1e9;
  return segmentAte(segments.front());
}

Eigen::Matrix<double, 6, 6> covarianceOf(const nav_msgs::Odometry& o) {
  Eigen::Matrix<double, 6, 6> C;
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 6; ++c) C(r, c) = o.pose.covariance[6 * r + c];
  return C;
}

}  // namespace

TEST(Interfaces, EveryTrackerProcessesTheBag) {
  g_run = std::make_unique<InterfaceRun>();
  const std::size_t frames = std::stoul(vitamin_e_test::privateParam("frames", "60"));
  for (auto* w : {&g_run->raw, &g_run->compressed, &g_run->rect, &g_run->few}) ASSERT_TRUE(w->waitForPublisher(30.0));
  ASSERT_TRUE(g_run->diagnostics.waitForPublisher(30.0));
  setPaused(false);
  // Every frame, also the bag's first when its image overtakes its camera_info (held for it):
  // the trackers all start from the same frame, so their trajectories compare.
  for (auto* w : {&g_run->raw, &g_run->compressed, &g_run->rect, &g_run->few}) {
    EXPECT_TRUE(w->waitFor([&](const Statuses& s) { return processed(s) >= frames; }, 120.0))
        << "frames processed: " << processed(w->messages()) << " of " << frames;
  }
}

// The 10 % of the issue, with a floor: at the test bag's 1 mm ATE, 10 % is 0.1 mm, less than
// what any change to the tracker moves the raw stream's own ATE (1.04-1.20 mm seen), so the
// same-within-10 % test would fail on noise; 0.3 mm is still 300x below reading a rectified
// stream with K and D (109 mm).
double sameWithin(double reference) { return std::max(0.1 * reference, 0.0003); }

// ~image_transport compressed reads <image>/compressed (here without the plugin,
// decoded with OpenCV) and tracks like the raw images. Only the compressed topic exists for
// this tracker (interfaces.test remaps it to /cam1), so its frames were decoded.
TEST(Interfaces, CompressedTrackedLikeRaw) {
  ASSERT_TRUE(g_run);
  const double raw = ateOf("tracking");
  const double jpeg = ateOf("tracking_compressed");
  RecordProperty("ate_raw_m", std::to_string(raw));
  RecordProperty("ate_compressed_m", std::to_string(jpeg));
  ROS_INFO("ATE raw %.5f m, compressed (jpeg 95) %.5f m", raw, jpeg);
  EXPECT_LT(raw, 0.05);
  EXPECT_LE(std::abs(jpeg - raw), sameWithin(raw)) << "raw " << raw << " m, compressed " << jpeg << " m";
  const auto c = g_run->compressed.messages();
  ASSERT_FALSE(c.empty());
  EXPECT_GT(c.back()->frames_tracked, 30u);
}

// image_rect with the same camera_info is taken as rectified (P, no distortion) and
// gives the raw stream's trajectory.
TEST(Interfaces, RectifiedLikeDistorted) {
  ASSERT_TRUE(g_run);
  const double raw = ateOf("tracking");
  const double rect = ateOf("tracking_rect");
  RecordProperty("ate_rectified_m", std::to_string(rect));
  ROS_INFO("ATE distorted %.5f m, rectified %.5f m", raw, rect);
  EXPECT_LT(raw, 0.05);
  EXPECT_LE(std::abs(rect - raw), sameWithin(raw)) << "distorted " << raw << " m, rectified " << rect << " m";
  const auto r = g_run->rect.messages();
  ASSERT_FALSE(r.empty());
  EXPECT_GT(r.back()->frames_tracked, 30u);
}

// Items 5 and 6: /diagnostics carries the tracker's status with its rates and state; the
// odometry covariance is positive definite and grows when a tenth of the points is tracked.
TEST(Interfaces, DiagnosticsAndCovariance) {
  ASSERT_TRUE(g_run);
  bool seen = false;
  EXPECT_TRUE(g_run->diagnostics.waitFor(
      [&](const std::vector<diagnostic_msgs::DiagnosticArray::ConstPtr>& arrays) {
        for (const auto& a : arrays) {
          for (const auto& s : a->status) {
            if (s.name.find("tracking: vitamin_e tracking") == std::string::npos) continue;
            std::map<std::string, std::string> kv;
            for (const auto& v : s.values) kv[v.key] = v.value;
            seen = kv.count("input rate [Hz]") && kv.count("processed rate [Hz]") && kv.count("state") &&
                   kv.count("tracked points") && kv.count("re-initializations") &&
                   kv.count("latency image -> pose mean [s]");
            // Not necessarily OK: on a loaded machine four trackers may process fewer frames
            // than arrive (a WARN); the levels are unit-tested (RosTrackingHealth.Levels).
            if (seen && kv["state"] == "tracking" && std::stod(kv["input rate [Hz]"]) > 0.0 &&
                std::stod(kv["processed rate [Hz]"]) > 0.0 && s.level != diagnostic_msgs::DiagnosticStatus::ERROR)
              return true;
          }
        }
        return false;
      },
      20.0))
      << (seen ? "a vitamin_e status, but never tracking with frame rates" : "no vitamin_e status with the keys");

  auto trace_by_stamp = [](const std::vector<nav_msgs::Odometry::ConstPtr>& odoms, bool* all_pd, int* estimated) {
    std::map<double, double> out;
    *all_pd = true;
    *estimated = 0;
    for (const auto& o : odoms) {
      const Eigen::Matrix<double, 6, 6> C = covarianceOf(*o);
      if (C(0, 0) >= 1e3) continue;  // no estimate for this frame (the initialization)
      ++*estimated;
      const Eigen::Matrix<double, 6, 6> S = 0.5 * (C + C.transpose());
      using Solver = Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>>;
      *all_pd &= Solver(S).eigenvalues().minCoeff() > 0.0;
      out[o->header.stamp.toSec()] = C.topLeftCorner<3, 3>().trace();
    }
    return out;
  };
  bool pd_many = false, pd_few = false;
  int n_many = 0, n_few = 0;
  const auto many = trace_by_stamp(g_run->odom.messages(), &pd_many, &n_many);
  const auto few = trace_by_stamp(g_run->odom_few.messages(), &pd_few, &n_few);
  EXPECT_TRUE(pd_many);
  EXPECT_TRUE(pd_few);
  EXPECT_GT(n_many, 30);
  EXPECT_GT(n_few, 30);
  // Frames both estimated: the position covariance with a tenth of the points, relative to all.
  std::vector<double> ratio;
  for (const auto& kv : many) {
    auto f = few.find(kv.first);
    if (f != few.end() && kv.second > 0.0) ratio.push_back(f->second / kv.second);
  }
  ASSERT_GT(ratio.size(), 20u);
  std::nth_element(ratio.begin(), ratio.begin() + static_cast<std::ptrdiff_t>(ratio.size() / 2), ratio.end());
  const double median = ratio[ratio.size() / 2];
  RecordProperty("covariance_ratio_few_over_all", std::to_string(median));
  ROS_INFO("position covariance with a tenth of the points / with all: median %.2f over %zu frames", median,
           ratio.size());
  EXPECT_GT(median, 2.0);
  const auto s_many = g_run->raw.messages(), s_few = g_run->few.messages();
  ASSERT_FALSE(s_many.empty());
  ASSERT_FALSE(s_few.empty());
  EXPECT_LT(s_few.back()->num_tracked * 5, s_many.back()->num_tracked) << "the few-points tracker is not sparse";
  g_run.reset();
}
