// Tracking against the map: pose from P3P + RANSAC, subspace Gauss-Newton bundle
// adjustment on every frame, keyframes by parallax, triangulation of new tracks.
#include <algorithm>
#include <cmath>
#include <unordered_set>

#include "system_impl.h"
#include "vitamin_e/geometry/pnp.h"
#include "vitamin_e/geometry/triangulation.h"
#include "vitamin_e/optimization/subspace_gn.h"

namespace vitamin_e::pipeline {

void System::Impl::track(FrameResult* result) {
  refreshCurrentLandmarks();
  reused_this_frame = 0;
  // Most map points of the previous frame gone at once (a cut, a sudden flip, a
  // covered lens): the few tracks left are not trusted for a pose.
  const std::size_t seen_before = mapped_last_frame;
  std::size_t seen_now = 0;
  for (map::Landmark* l : cur_landmarks) seen_now += l ? 1 : 0;
  const bool vanished = seen_before >= 100 && seen_now * 5 < seen_before;
  for (map::Landmark* l : cur_landmarks) {
    if (l) l->last_seen_frame = frame_index;
  }
  std::string why;
  Eigen::Isometry3d T_w_c;
  {
    const auto t0 = std::chrono::steady_clock::now();
    if (vanished) {
      why = "only " + std::to_string(seen_now) + " of the " + std::to_string(seen_before) +
            " map points of the previous frame are still tracked";
    }
    const bool ok = !vanished && estimatePose(&T_w_c, &why);
    const double ms = elapsedMs(t0);
    addTiming("pose", ms);
    result->timing_ms["pose"] = ms;
    if (ok) {
      // Localized: new tracks where old map points project take them over.
      const auto t1 = std::chrono::steady_clock::now();
      T_w_cur = T_w_c;
      reused_this_frame = static_cast<std::size_t>(reuseMapPoints());
      const double reuse_ms = elapsedMs(t1);
      addTiming("reuse", reuse_ms);
      result->timing_ms["reuse"] = reuse_ms;
    }
    if (!ok) {
      ++init_retries;
      resetMap();
      // This frame becomes the reference of the next initialization.
      PendingFrame pf;
      pf.frame_index = frame_index;
      pf.timestamp = cur_t;
      pf.timestamp_text = cur_text;
      for (const FrameTrack& t : cur_tracks) pf.xy.emplace(t.id, t.xy);
      pending.push_back(std::move(pf));
      state = TrackingState::kLost;
      result->state = TrackingState::kLost;
      result->message = "lost: " + why + "; re-initializing";
      return;
    }
  }
  T_w_cur = T_w_c;
  cur_covariance_valid = false;
  {
    const auto t0 = std::chrono::steady_clock::now();
    bundleAdjust(false);
    const double ms = elapsedMs(t0);
    addTiming("ba", ms);
    result->timing_ms["ba"] = ms;
  }
  // A pose must be finite and must not jump: a step far beyond the scene depth
  // is a failure, not motion.
  const double step = (T_w_cur.translation() - T_w_last.translation()).norm();
  if (!T_w_cur.matrix().allFinite() || step > config.max_step_depth_ratio * scene_depth) {
    ++init_retries;
    resetMap();
    state = TrackingState::kLost;
    result->state = TrackingState::kLost;
    result->message = "lost: pose jumped by " + std::to_string(step) + " (scene depth " +
                      std::to_string(scene_depth) + "); re-initializing";
    return;
  }
  recordPose(frame_index, cur_t, cur_text, T_w_cur);
  T_last_prev = T_w_last.inverse() * T_w_cur;
  T_w_last = T_w_cur;
  have_last_pose = true;
  ++frames_since_keyframe;
  {
    const auto t0 = std::chrono::steady_clock::now();
    if (needKeyframe()) {
      insertKeyframe();
      triangulateNewPoints();
      refreshCurrentLandmarks();
      bundleAdjust(true);
      T_w_cur = map.keyframes().back().T_w_c;
      T_w_last = T_w_cur;
      if (!trajectory.empty()) trajectory.back().T_w_c = T_w_cur;
    }
    // Median depth of the mapped points in view: the map's scale at this place.
    std::vector<double> depths;
    const Eigen::Isometry3d T_c_w = T_w_cur.inverse();
    for (const map::Landmark* l : cur_landmarks) {
      if (l) depths.push_back((T_c_w * l->p_w).z());
    }
    if (depths.size() > 20) scene_depth = std::max(1e-6, upperMedian(depths));
    const double ms = elapsedMs(t0);
    addTiming("map", ms);
    result->timing_ms["map"] = ms;
  }
  state = TrackingState::kTracking;
  result->state = TrackingState::kTracking;
  result->pose_valid = true;
  result->T_w_c = T_w_cur;
  result->T_w_c_covariance = cur_covariance;
  result->T_w_c_covariance_valid = cur_covariance_valid;
  // Map points handed to tracks by map reuse this frame are left out: they are
  // mostly on tracks born a frame ago, half of which end at their next step, so
  // counting them would make ordinary churn look like the map vanishing.
  mapped_last_frame = 0;
  for (map::Landmark* l : cur_landmarks) mapped_last_frame += l ? 1 : 0;
  mapped_last_frame -= std::min(mapped_last_frame, reused_this_frame);
}

bool System::Impl::estimatePose(Eigen::Isometry3d* T_w_c, std::string* why) {
  std::vector<Eigen::Vector3d> p_w;
  std::vector<Eigen::Vector2d> xy;
  std::vector<map::Landmark*> used;
  for (std::size_t i = 0; i < cur_tracks.size(); ++i) {
    if (map::Landmark* l = cur_landmarks[i]) {
      p_w.push_back(l->p_w);
      xy.push_back(cur_tracks[i].xy);
      used.push_back(l);
    }
  }
  if (static_cast<int>(p_w.size()) < config.min_pose_inliers) {
    *why = "only " + std::to_string(p_w.size()) + " tracked map points";
    return false;
  }
  const Eigen::Isometry3d guess = T_w_last * T_last_prev;
  geometry::PnpResult r = geometry::solvePnpRansac(p_w, xy, config.pnp, &guess);
  if (!r.ok || r.num_inliers < config.min_pose_inliers) {
    *why = "pose estimation failed (" + std::to_string(r.num_inliers) + " inliers of " + std::to_string(p_w.size()) +
           ")";
    return false;
  }
  std::vector<std::uint64_t> dropped;
  for (std::size_t i = 0; i < used.size(); ++i) {
    if (i < r.inliers.size() && !r.inliers[i] && ++used[i]->outlier_count >= config.max_outlier_count) {
      dropped.push_back(used[i]->id);
    }
  }
  removeLandmarks(dropped);
  *T_w_c = r.T_w_c;
  return true;
}

void System::Impl::bundleAdjust(bool keyframe_window) {
  optimization::BaProblem problem;
  problem.fx = camera.fx();
  problem.fy = camera.fy();
  problem.cx = camera.cx();
  problem.cy = camera.cy();
  const auto& kfs = map.keyframes();
  // Cameras: the window's keyframes; in per-frame mode the current frame is
  // appended as the only free camera.
  // Keyframe BA: the newest ba_free_keyframes are free, never the oldest
  // ba_fixed_keyframes (gauge: pose and scale); with two keyframes only the
  // first is fixed.
  const int num_kf = static_cast<int>(kfs.size());
  const int first_free =
      std::max(std::min(config.ba_fixed_keyframes, num_kf - 1), num_kf - config.ba_free_keyframes);
  for (int k = 0; k < num_kf; ++k) {
    optimization::BaCamera c;
    c.T_w_c = kfs[k].T_w_c;
    c.fixed = !keyframe_window || k < first_free;
    problem.cameras.push_back(c);
  }
  int current_cam = -1;
  if (!keyframe_window) {
    optimization::BaCamera c;
    c.T_w_c = T_w_cur;
    c.fixed = false;
    current_cam = static_cast<int>(problem.cameras.size());
    problem.cameras.push_back(c);
  }
  // Keyframe frame index -> camera index (the window is small).
  auto camera_of = [&](std::uint64_t keyframe) -> int {
    for (int k = num_kf - 1; k >= 0; --k) {
      if (kfs[k].frame_index == keyframe) return k;
    }
    return -1;
  };
  auto to_px = [&](const Eigen::Vector2d& xy) {
    return Eigen::Vector2d(camera.fx() * xy.x() + camera.cx(), camera.fy() * xy.y() + camera.cy());
  };
  // Points: per frame, those the current frame sees; per keyframe, those the
  // free keyframes see. Each comes with all its keyframe observations.
  std::vector<map::Landmark*> points;
  // A point seen by fewer than two cameras of the problem has no depth: fixed.
  // So are revived points, if configured: they anchor the pose to the older map.
  auto add_point = [&](map::Landmark* l, int extra_observations) {
    const int idx = static_cast<int>(problem.points.size());
    problem.points.push_back({l->p_w, false});
    points.push_back(l);
    int seen = extra_observations;
    for (const map::LandmarkObservation& o : l->observations) {
      const int cam = camera_of(o.keyframe);
      if (cam >= 0) {
        problem.observations.push_back({cam, idx, to_px(o.xy)});
        ++seen;
      }
    }
    problem.points.back().fixed = seen < 2 || (l->revived && config.reuse_fix_revived);
    return idx;
  };
  if (keyframe_window) {
    std::unordered_set<std::uint64_t> added;
    for (int k = first_free; k < num_kf; ++k) {
      for (const auto& obs : kfs[k].observations) {
        map::Landmark* l = map.landmark(obs.first);
        if (l && added.insert(obs.first).second) add_point(l, 0);
      }
    }
  } else {
    for (std::size_t i = 0; i < cur_tracks.size(); ++i) {
      map::Landmark* l = cur_landmarks[i];
      if (!l) continue;
      const int p = add_point(l, 1);
      problem.observations.push_back({current_cam, p, to_px(cur_tracks[i].xy)});
    }
  }
  if (problem.points.empty()) return;
  optimization::BaOptions options = config.ba;
  options.max_sweeps = keyframe_window ? config.ba_keyframe_sweeps : config.ba_frame_sweeps;
  options.compute_covariance = !keyframe_window;  // the frame's pose covariance (FrameResult)
  const optimization::BaSummary summary = optimization::solveSubspaceGaussNewton(problem, options);
  if (current_cam >= 0 && !summary.camera_covariance_valid.empty()) {
    cur_covariance = summary.camera_covariance[current_cam];
    cur_covariance_valid = summary.camera_covariance_valid[current_cam];
  }

  // Write back (only finite results).
  for (std::size_t k = 0; k < kfs.size(); ++k) {
    if (problem.cameras[k].T_w_c.matrix().allFinite()) map.keyframes()[k].T_w_c = problem.cameras[k].T_w_c;
  }
  if (current_cam >= 0 && problem.cameras[current_cam].T_w_c.matrix().allFinite()) {
    T_w_cur = problem.cameras[current_cam].T_w_c;
  }
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (problem.points[i].p_w.allFinite()) points[i]->p_w = problem.points[i].p_w;
  }
  // Observations far off after the optimization mark their points; repeated
  // offenders are removed from the map and their tracks dropped.
  std::vector<bool> bad(points.size(), false);
  for (std::size_t o = 0; o < problem.observations.size() && o < summary.residual_px.size(); ++o) {
    if (summary.residual_px[o] > config.max_reprojection_px) bad[problem.observations[o].point] = true;
  }
  std::vector<std::uint64_t> dropped;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (bad[i] && ++points[i]->outlier_count >= config.max_outlier_count) dropped.push_back(points[i]->id);
  }
  removeLandmarks(dropped);
}

void System::Impl::refreshCurrentLandmarks() {
  cur_landmarks.resize(cur_tracks.size());
  for (std::size_t i = 0; i < cur_tracks.size(); ++i) cur_landmarks[i] = map.landmark(cur_tracks[i].id);
}

void System::Impl::removeLandmarks(const std::vector<std::uint64_t>& ids) {
  if (ids.empty()) return;
  for (std::uint64_t id : ids) map.removeLandmark(id);
  dropTracksLater(ids);
  refreshCurrentLandmarks();
}

bool System::Impl::needKeyframe() const {
  if (map.keyframes().empty()) return true;
  const map::Keyframe& kf = map.keyframes().back();
  const Eigen::Matrix3d R_cur_kf = (T_w_cur.inverse() * kf.T_w_c).rotation();
  std::vector<double> parallax;
  std::size_t mapped = 0;
  for (std::size_t i = 0; i < cur_tracks.size(); ++i) {
    const FrameTrack& t = cur_tracks[i];
    if (cur_landmarks[i]) ++mapped;
    auto it = kf.observations.find(t.id);
    if (it == kf.observations.end()) continue;
    const Eigen::Vector3d f = R_cur_kf * it->second.homogeneous();
    if (f.z() <= 1e-9) continue;
    parallax.push_back((f.hnormalized() - t.xy).norm() * camera.fx());
  }
  const double med = upperMedian(parallax);
  if (med >= config.keyframe_parallax_px) return true;
  const double mapped_ratio = cur_tracks.empty() ? 0.0 : static_cast<double>(mapped) / cur_tracks.size();
  return mapped_ratio < config.keyframe_min_mapped_ratio && med >= 0.3 * config.keyframe_parallax_px;
}

void System::Impl::insertKeyframe() {
  map::Keyframe kf;
  kf.frame_index = frame_index;
  kf.timestamp = cur_t;
  kf.T_w_c = T_w_cur;
  for (const FrameTrack& t : cur_tracks) kf.observations.emplace(t.id, t.xy);
  map.addKeyframe(std::move(kf));
  frames_since_keyframe = 0;
}

int System::Impl::triangulateNewPoints() {
  const auto& kfs = map.keyframes();
  int created = 0;
  std::vector<Eigen::Isometry3d> poses;
  std::vector<Eigen::Vector2d> obs;
  for (std::size_t i = 0; i < cur_tracks.size(); ++i) {
    const FrameTrack& t = cur_tracks[i];
    if (cur_landmarks[i]) continue;
    poses.clear();
    obs.clear();
    for (const map::Keyframe& kf : kfs) {
      auto it = kf.observations.find(t.id);
      if (it == kf.observations.end()) continue;
      poses.push_back(kf.T_w_c);
      obs.push_back(it->second);
    }
    if (poses.size() < 2) continue;
    geometry::TriangulationResult tr = geometry::triangulatePoint(poses, obs, config.triangulation);
    if (!tr.ok) continue;
    map::Landmark& l = map.addLandmark(t.id, tr.p_w, t.intensity);
    l.polarity = t.polarity;
    l.num_observations = static_cast<int>(poses.size());
    l.last_seen_frame = frame_index;
    ++created;
  }
  return created;
}

}  // namespace vitamin_e::pipeline
