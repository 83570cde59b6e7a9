#pragma once
// Private state of pipeline::System (not installed).
#include <deque>
#include <mutex>
#include <unordered_map>
#include <vector>

#include "vitamin_e/map/map.h"
#include "vitamin_e/pipeline/system.h"
#include "vitamin_e/pipeline/tracked_frame.h"
#include "vitamin_e/tracking/dense_tracker.h"

namespace vitamin_e::pipeline {

// A frame seen while initializing, localized once the map exists.
struct PendingFrame {
  std::uint64_t frame_index;
  double timestamp;
  std::string timestamp_text;
  std::unordered_map<std::uint64_t, Eigen::Vector2d> xy;
};

struct System::Impl {
  Impl(const SystemConfig& config, const camera::Camera& camera);

  FrameResult process(const cv::Mat& image, double timestamp, const std::string& timestamp_text);
  // The two stages of process(): tracking (tracker + undistortion) and mapping
  // (initialization, pose, BA, map). In the pipelined mode they run on two
  // threads; they share nothing but the thread-safe pending_drops and timings.
  TrackedFrame trackStage(const cv::Mat& image, double timestamp, const std::string& timestamp_text);
  FrameResult mapStage(TrackedFrame&& frame);
  void addTiming(const std::string& stage, double ms);
  void dropTracksLater(const std::vector<std::uint64_t>& ids);  // applied before the next tracking
  void resetMap();

  // stages (system_init.cpp, system_track.cpp)
  void initialize(FrameResult* result);
  void track(FrameResult* result);
  bool estimatePose(Eigen::Isometry3d* T_w_c, std::string* why);
  void bundleAdjust(bool keyframe_window);
  bool needKeyframe() const;
  void insertKeyframe();
  int triangulateNewPoints();
  int reuseMapPoints();  // system_reuse.cpp
  void localizePendingFrames();
  void recordPose(std::uint64_t frame_index, double t, const std::string& text, const Eigen::Isometry3d& T_w_c);
  void fillResultPoints(FrameResult* result) const;
  void refreshCurrentLandmarks();  // cur_landmarks from cur_tracks
  void removeLandmarks(const std::vector<std::uint64_t>& ids);  // from the map and the tracker

  SystemConfig config;
  camera::Camera camera;
  tracking::DenseTracker tracker;
  map::Map map;
  StageTimings timings;
  std::mutex timings_mutex;
  std::mutex drops_mutex;
  std::vector<std::uint64_t> pending_drops;

  // tracking-stage state
  std::uint64_t next_frame_index = 0;
  bool have_last_stamp = false;
  double last_stamp = 0.0;

  // mapping-stage state
  std::uint64_t frame_index = 0;  // index of the frame being mapped
  std::uint64_t frames_processed = 0;
  std::uint64_t frames_tracked = 0;
  long long first_init_frame = -1;        // frame index of the first successful initialization
  std::uint64_t localized_before_init = 0; // poses recorded for frames before it
  int init_retries = 0;
  bool initialized_once = false;
  TrackingState state = TrackingState::kInitializing;

  // current frame
  double cur_t = 0.0;
  std::string cur_text;
  std::vector<FrameTrack> cur_tracks;
  std::vector<map::Landmark*> cur_landmarks;  // per cur_tracks entry, null if unmapped
  std::size_t mapped_last_frame = 0;  // map points tracked in the last tracked frame (not counting reuse)
  std::size_t reused_this_frame = 0;  // map points taken over by new tracks in this frame
  Eigen::Isometry3d T_w_cur = Eigen::Isometry3d::Identity();
  // T_w_cur's covariance from the last per-frame BA (FrameResult::T_w_c_covariance).
  Eigen::Matrix<double, 6, 6> cur_covariance = Eigen::Matrix<double, 6, 6>::Zero();
  bool cur_covariance_valid = false;

  // motion model
  bool have_last_pose = false;
  Eigen::Isometry3d T_w_last = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d T_last_prev = Eigen::Isometry3d::Identity();  // last relative motion (T_c_{k-1} <- c_k)
  double scene_depth = 1.0;  // median depth of the map seen from the camera, map units

  // initialization
  std::deque<PendingFrame> pending;  // pending.front() is the reference frame
  std::uint64_t frames_since_keyframe = 0;
  std::uint64_t reused_points = 0;
  std::uint64_t dormant_cursor = 0;  // next dormant entry to check (in retirement order, see Map::dormantDropped)  // map points taken over by new tracks (map reuse)

  std::vector<TrajectoryEntry> trajectory;
};

}  // namespace vitamin_e::pipeline
