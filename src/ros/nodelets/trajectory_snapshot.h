#pragma once
// What ~save_trajectory reads while the SLAM thread goes on: the finished segments
// (already in the map frame) and the current segment's poses in the core's world with
// their map's T_map_w. The SLAM thread updates it after every frame (appending: only the
// newest pose can still change); any thread takes a copy.
#include <mutex>
#include <vector>

#include "vitamin_e/pipeline/session.h"

namespace vitamin_e_ros {

class TrajectorySnapshot {
 public:
  // SLAM thread. T_map_w: the map frame of the session's current map; segments finished
  // since the last update are taken into the map frame with it (a reset updates before the
  // map frame changes).
  void update(const vitamin_e::pipeline::Session& session, const Eigen::Isometry3d& T_map_w) {
    const auto& finished = session.finishedSegments();
    const auto& trajectory = session.system().trajectory();
    const std::size_t begin = session.segmentBegin();
    std::lock_guard<std::mutex> lock(mutex_);
    for (std::size_t k = finished_.size(); k < finished.size(); ++k) {
      vitamin_e::pipeline::TrajectorySegment s = finished[k];
      for (auto& e : s.poses) e.T_w_c = T_map_w * e.T_w_c;
      finished_.push_back(std::move(s));
    }
    if (current_.number != session.segment() || trajectory.size() < begin) current_.poses.clear();
    current_.number = session.segment();
    current_.map = session.map();
    current_.note = session.segmentNote();
    auto& poses = current_.poses;
    // From the last pose copied on (it may have been refined since), all of them when the
    // trajectory is not the one copied so far.
    std::size_t from = poses.empty() ? 0 : poses.size() - 1;
    if (trajectory.size() < begin + poses.size()) from = 0;
    poses.resize(from);
    if (begin + from < trajectory.size()) {
      poses.insert(poses.end(), trajectory.begin() + static_cast<std::ptrdiff_t>(begin + from), trajectory.end());
    }
    T_map_w_ = T_map_w;
  }

  // Any thread: every segment in the map frame, the current one last.
  std::vector<vitamin_e::pipeline::TrajectorySegment> segments() const {
    std::lock_guard<std::mutex> lock(mutex_);
    std::vector<vitamin_e::pipeline::TrajectorySegment> all = finished_;
    vitamin_e::pipeline::TrajectorySegment current = current_;
    for (auto& e : current.poses) e.T_w_c = T_map_w_ * e.T_w_c;
    if (!current.poses.empty() || all.empty()) all.push_back(std::move(current));
    return all;
  }

 private:
  mutable std::mutex mutex_;
  std::vector<vitamin_e::pipeline::TrajectorySegment> finished_;
  vitamin_e::pipeline::TrajectorySegment current_;
  Eigen::Isometry3d T_map_w_ = Eigen::Isometry3d::Identity();
};

}  // namespace vitamin_e_ros
