// Monocular initialization: wait for parallax between a reference frame and the
// current one, build the first two keyframes and landmarks from the essential
// matrix, then localize the frames seen in between against that map.
#include <algorithm>
#include <cmath>

#include "system_impl.h"
#include "vitamin_e/geometry/pnp.h"
#include "vitamin_e/geometry/two_view.h"

namespace vitamin_e::pipeline {

void System::Impl::initialize(FrameResult* result) {
  const auto t0 = std::chrono::steady_clock::now();
  state = TrackingState::kInitializing;
  result->state = TrackingState::kInitializing;
  PendingFrame pf;
  pf.frame_index = frame_index;
  pf.timestamp = cur_t;
  pf.timestamp_text = cur_text;
  for (const FrameTrack& t : cur_tracks) pf.xy.emplace(t.id, t.xy);

  auto restart_reference = [&](const std::string& why) {
    pending.clear();
    pending.push_back(std::move(pf));
    result->message = why;
  };

  if (pending.empty()) {
    restart_reference("initializing: reference frame set");
    return;
  }
  const PendingFrame& ref = pending.front();
  std::vector<Eigen::Vector2d> xy0, xy1;
  std::vector<std::uint64_t> ids;
  std::vector<double> disparity;
  for (const FrameTrack& t : cur_tracks) {
    auto it = ref.xy.find(t.id);
    if (it == ref.xy.end()) continue;
    xy0.push_back(it->second);
    xy1.push_back(t.xy);
    ids.push_back(t.id);
    disparity.push_back((t.xy - it->second).norm() * camera.fx());
  }
  if (static_cast<int>(ids.size()) < config.min_init_tracks) {
    restart_reference("initializing: too few tracks survive from the reference frame (" +
                      std::to_string(ids.size()) + "); new reference");
    return;
  }
  pending.push_back(pf);
  while (static_cast<int>(pending.size()) > config.init_max_pending_frames) pending.erase(pending.begin() + 1);

  const double med_disp = upperMedian(disparity);
  if (med_disp < config.init_min_disparity_px) {
    result->message = "initializing: waiting for parallax (median disparity " + std::to_string(med_disp) + " px)";
    addTiming("init", elapsedMs(t0));
    return;
  }
  geometry::TwoViewResult tv = geometry::initializeTwoView(xy0, xy1, config.init);
  if (!tv.ok) {
    result->message = "initializing: " + tv.reason;
    if (pending.size() >= static_cast<std::size_t>(config.init_max_pending_frames)) {
      PendingFrame cur = pending.back();
      pending.clear();
      pending.push_back(std::move(cur));
      result->message += "; new reference";
    }
    addTiming("init", elapsedMs(t0));
    return;
  }

  // Anchor: the first map defines the world (first reference camera = origin);
  // after a loss, the new map continues from the last known pose at the last scale.
  Eigen::Isometry3d T_w_c0 = Eigen::Isometry3d::Identity();
  double scale = 1.0;
  if (initialized_once && have_last_pose) {
    T_w_c0 = T_w_last;
    scale = scene_depth;
  }
  Eigen::Isometry3d T_c1_c0 = tv.T_c1_c0;
  T_c1_c0.translation() *= scale;
  const Eigen::Isometry3d T_w_c1 = T_w_c0 * T_c1_c0.inverse();

  map.clear();
  map::Keyframe kf0;
  kf0.frame_index = ref.frame_index;
  kf0.timestamp = ref.timestamp;
  kf0.T_w_c = T_w_c0;
  map::Keyframe kf1;
  kf1.frame_index = frame_index;
  kf1.timestamp = cur_t;
  kf1.T_w_c = T_w_c1;
  std::unordered_map<std::uint64_t, const FrameTrack*> track_of;
  for (const FrameTrack& t : cur_tracks) track_of[t.id] = &t;
  for (std::size_t i = 0; i < ids.size(); ++i) {
    kf0.observations.emplace(ids[i], xy0[i]);
    kf1.observations.emplace(ids[i], xy1[i]);
    if (i < tv.valid.size() && tv.valid[i]) {
      auto t = track_of.find(ids[i]);
      map::Landmark& l = map.addLandmark(ids[i], T_w_c0 * (scale * tv.points_c0[i]),
                                         t == track_of.end() ? 0 : t->second->intensity);
      l.polarity = t == track_of.end() ? 0 : t->second->polarity;
    }
  }
  // Tracks born after the reference: observed by the second keyframe only.
  for (const FrameTrack& t : cur_tracks) kf1.observations.emplace(t.id, t.xy);
  map.addKeyframe(std::move(kf0));
  map.addKeyframe(std::move(kf1));
  for (auto& kv : map.landmarks()) {
    kv.second.last_seen_frame = frame_index;
  }

  T_w_cur = T_w_c1;
  state = TrackingState::kTracking;
  frames_since_keyframe = 0;
  bundleAdjust(true);

  const PendingFrame ref_copy = pending.front();
  recordPose(ref_copy.frame_index, ref_copy.timestamp, ref_copy.timestamp_text, map.keyframes().front().T_w_c);
  localizePendingFrames();
  T_w_cur = map.keyframes().back().T_w_c;
  if (first_init_frame < 0) first_init_frame = static_cast<long long>(frame_index);
  recordPose(frame_index, cur_t, cur_text, T_w_cur);
  // Motion model from the last localized in-between frame, if any.
  T_last_prev = Eigen::Isometry3d::Identity();
  if (trajectory.size() >= 2) {
    const Eigen::Isometry3d& T_w_prev = trajectory[trajectory.size() - 2].T_w_c;
    T_last_prev = T_w_prev.inverse() * T_w_cur;
  }
  T_w_last = T_w_cur;
  have_last_pose = true;
  initialized_once = true;
  pending.clear();
  refreshCurrentLandmarks();
  mapped_last_frame = 0;
  for (map::Landmark* l : cur_landmarks) mapped_last_frame += l ? 1 : 0;
  result->state = TrackingState::kTracking;
  result->pose_valid = true;
  result->T_w_c = T_w_cur;
  result->message = "initialized: " + std::to_string(map.landmarks().size()) + " points, parallax " +
                    std::to_string(tv.median_parallax_deg) + " deg";
  // Planar scenes (two_view.h): say where the motion came from, and say so when two views
  // could not tell two different motions apart (the map may then be built on the wrong one).
  if (tv.used_homography) {
    result->message += "; planar scene: motion from the homography, not the essential matrix (best different motion: " +
                       std::to_string(tv.num_rival_inliers) + " points in front of both cameras)";
  }
  if (tv.ambiguous) {
    result->message += "; WARNING: ambiguous initialization, planar scene: another motion explains the views as well (" +
                       std::to_string(tv.num_rival_inliers) + " of " + std::to_string(tv.num_inliers) + " points)";
  }
  addTiming("init", elapsedMs(t0));
}

void System::Impl::localizePendingFrames() {
  // Frames strictly between the reference and the current frame.
  if (pending.size() < 3) return;
  Eigen::Isometry3d guess = map.keyframes().front().T_w_c;
  for (std::size_t k = 1; k + 1 < pending.size(); ++k) {
    const PendingFrame& f = pending[k];
    std::vector<Eigen::Vector3d> p_w;
    std::vector<Eigen::Vector2d> xy;
    for (const auto& kv : f.xy) {
      if (const map::Landmark* l = map.landmark(kv.first)) {
        p_w.push_back(l->p_w);
        xy.push_back(kv.second);
      }
    }
    if (static_cast<int>(p_w.size()) < config.min_pose_inliers) continue;
    geometry::PnpResult r = geometry::solvePnpRansac(p_w, xy, config.pnp, &guess);
    if (!r.ok || r.num_inliers < config.min_pose_inliers) continue;
    recordPose(f.frame_index, f.timestamp, f.timestamp_text, r.T_w_c);
    guess = r.T_w_c;
  }
}

}  // namespace vitamin_e::pipeline
