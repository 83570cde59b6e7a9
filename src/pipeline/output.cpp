// Trajectory (TUM) and map (PLY) writers shared by the offline runner and ROS services, and the
// names of the frame result's enums.
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>

#include "vitamin_e/pipeline/system.h"

namespace vitamin_e::pipeline {

const char* toString(TrackingState state) {
  switch (state) {
    case TrackingState::kInitializing: return "initializing";
    case TrackingState::kTracking: return "tracking";
    case TrackingState::kLost: return "lost";
    case TrackingState::kRelocalizing: return "relocalizing";
  }
  return "unknown";
}

const char* toString(StateReason reason) {
  switch (reason) {
    case StateReason::kWaitingForMap: return "waiting_for_map";
    case StateReason::kInitialized: return "initialized";
    case StateReason::kTracked: return "tracked";
    case StateReason::kPoseFailed: return "pose_failed";
    case StateReason::kPoseJumped: return "pose_jumped";
    case StateReason::kRelocalized: return "relocalized";
    case StateReason::kNotRelocalized: return "not_relocalized";
    case StateReason::kRelocalizationTimedOut: return "relocalization_timed_out";
    case StateReason::kSkipped: return "skipped";
  }
  return "unknown";
}

const char* toString(RelocalizationOutcome outcome) {
  switch (outcome) {
    case RelocalizationOutcome::kNotTried: return "";
    case RelocalizationOutcome::kRelocalized: return "relocalized";
    case RelocalizationOutcome::kNotFound: return "not_found";
    case RelocalizationOutcome::kDidNotHold: return "did_not_hold";
  }
  return "unknown";
}

FramePose poseOf(const FrameResult& result) {
  FramePose pose;
  pose.frame_index = result.frame_index;
  pose.timestamp = result.timestamp;
  pose.T_w_c = result.T_w_c;
  pose.T_w_c_covariance = result.T_w_c_covariance;
  pose.T_w_c_covariance_valid = result.T_w_c_covariance_valid;
  pose.keyframe = result.diagnostics.keyframe;
  return pose;
}

void framePointsInCamera(const FrameResult& result, std::vector<std::uint64_t>* ids,
                         std::vector<Eigen::Vector3d>* p_c) {
  ids->clear();
  p_c->clear();
  if (!result.pose_valid) return;
  const Eigen::Isometry3d T_c_w = result.T_w_c.inverse();
  for (const FramePoint& p : result.points) {
    if (!p.has_position) continue;
    const Eigen::Vector3d q = T_c_w * p.p_w;
    if (!q.allFinite() || q.z() <= 0.0) continue;
    ids->push_back(p.track_id);
    p_c->push_back(q);
  }
}

namespace {
bool fail(std::string* error, const std::string& message) {
  if (error) *error = message;
  return false;
}
}  // namespace

bool saveTrajectoryTum(const std::vector<TrajectoryEntry>& trajectory, const std::string& path, std::string* error) {
  std::ofstream out(path);
  if (!out) return fail(error, "cannot write trajectory to '" + path + "': " + std::strerror(errno));
  out << "# timestamp tx ty tz qx qy qz qw (T_w_c, camera in world)\n";
  char line[256];
  for (const TrajectoryEntry& e : trajectory) {
    const Eigen::Vector3d t = e.T_w_c.translation();
    Eigen::Quaterniond q(e.T_w_c.rotation());
    q.normalize();
    if (!t.allFinite() || !q.coeffs().allFinite()) continue;  // never write a non-finite pose
    const std::string stamp = e.timestamp_text.empty() ? [&] {
      char buf[64];
      std::snprintf(buf, sizeof(buf), "%.9f", e.timestamp);
      return std::string(buf);
    }() : e.timestamp_text;
    std::snprintf(line, sizeof(line), " %.9f %.9f %.9f %.9f %.9f %.9f %.9f\n", t.x(), t.y(), t.z(), q.x(), q.y(), q.z(),
                  q.w());
    out << stamp << line;
  }
  out.flush();
  if (!out) return fail(error, "error while writing trajectory to '" + path + "'");
  return true;
}

bool saveMapPly(const std::vector<MapPoint3>& points, const std::string& path, std::string* error) {
  std::ofstream out(path, std::ios::binary);
  if (!out) return fail(error, "cannot write map to '" + path + "': " + std::strerror(errno));
  std::size_t n = 0;
  for (const MapPoint3& p : points) n += p.p_w.allFinite() ? 1 : 0;
  out << "ply\nformat binary_little_endian 1.0\ncomment vitamin_e map points (world frame)\n"
      << "element vertex " << n << "\nproperty float x\nproperty float y\nproperty float z\n"
      << "property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n";
  for (const MapPoint3& p : points) {
    if (!p.p_w.allFinite()) continue;
    const float xyz[3] = {static_cast<float>(p.p_w.x()), static_cast<float>(p.p_w.y()), static_cast<float>(p.p_w.z())};
    const unsigned char rgb[3] = {p.intensity, p.intensity, p.intensity};
    out.write(reinterpret_cast<const char*>(xyz), sizeof(xyz));
    out.write(reinterpret_cast<const char*>(rgb), sizeof(rgb));
  }
  out.flush();
  if (!out) return fail(error, "error while writing map to '" + path + "'");
  return true;
}

}  // namespace vitamin_e::pipeline
