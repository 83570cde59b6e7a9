#include "vitamin_e/pipeline/mapper.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <unordered_set>

#include "vitamin_e/common/timing.h"
#include "vitamin_e/geometry/triangulation.h"
#include "vitamin_e/optimization/subspace_gn.h"

namespace vitamin_e::pipeline {

namespace {
// The keys of FrameDiagnostics::triangulation_rejected_by.
const char* rejectionName(geometry::TriangulationCheck failed) {
  switch (failed) {
    case geometry::TriangulationCheck::kCheirality: return "cheirality";
    case geometry::TriangulationCheck::kParallax: return "parallax";
    case geometry::TriangulationCheck::kReprojection: return "reprojection";
    default: return "other";
  }
}
}  // namespace

Mapper::Mapper(const SystemConfig& config, const camera::Camera& camera) : config_(config), camera_(camera) {}

FrameRefinement Mapper::refineFrame(const FrameContext& frame, const Eigen::Isometry3d& T_w_c,
                                    const map::Map& map) const {
  return bundleAdjust(&frame, T_w_c, map);
}

MapUpdate Mapper::optimizeWindow(const map::Map& map) const {
  return bundleAdjust(nullptr, Eigen::Isometry3d::Identity(), map).update;
}

FrameRefinement Mapper::bundleAdjust(const FrameContext* frame, const Eigen::Isometry3d& T_w_c,
                                     const map::Map& map) const {
  const bool keyframe_window = frame == nullptr;
  optimization::BaProblem problem;
  problem.K = camera_.pinhole();
  const auto& kfs = map.keyframes();
  // Cameras: the window's keyframes; in per-frame mode the current frame is
  // appended as the only free camera.
  // Keyframe BA: the newest ba_free_keyframes are free (or, with the experimental
  // ba_free_min_shared, those sharing the newest keyframe's view), never the oldest
  // ba_fixed_keyframes (gauge: pose and scale); with two keyframes only the first is fixed.
  const int num_kf = static_cast<int>(kfs.size());
  const int gauge = std::min(config_.ba_fixed_keyframes, num_kf - 1);
  std::vector<bool> free_kf(static_cast<std::size_t>(num_kf), false);
  if (keyframe_window && config_.ba_free_min_shared > 0.0 && num_kf > 0) {
    // Free the keyframes that still see a good share of what the newest one sees.
    const auto& newest = kfs.back().observations;
    int mapped = 0;
    for (const auto& o : newest) mapped += map.landmark(o.first) ? 1 : 0;
    for (int k = gauge; k < num_kf; ++k) {
      int shared = 0;
      for (const auto& o : kfs[k].observations) shared += (newest.count(o.first) && map.landmark(o.first)) ? 1 : 0;
      free_kf[k] = k == num_kf - 1 || shared >= config_.ba_free_min_shared * mapped;
    }
  } else if (keyframe_window) {
    for (int k = std::max(gauge, num_kf - config_.ba_free_keyframes); k < num_kf; ++k) free_kf[k] = true;
  }
  for (int k = 0; k < num_kf; ++k) {
    optimization::BaCamera c;
    c.T_w_c = kfs[k].T_w_c;
    c.fixed = !free_kf[k];
    problem.cameras.push_back(c);
  }
  int current_cam = -1;
  if (!keyframe_window) {
    optimization::BaCamera c;
    c.T_w_c = T_w_c;
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
  // Points: per frame, those the current frame sees; per keyframe, those the
  // free keyframes see. Each comes with all its keyframe observations.
  std::vector<const map::Landmark*> points;
  // A point seen by fewer than two cameras of the problem has no depth: fixed.
  // So are revived points, if configured: they anchor the pose to the older map.
  auto add_point = [&](const map::Landmark* l, int extra_observations) {
    const int idx = static_cast<int>(problem.points.size());
    problem.points.push_back({l->p_w, false});
    points.push_back(l);
    int seen = extra_observations;
    for (const map::LandmarkObservation& o : l->observations) {
      const int cam = camera_of(o.keyframe);
      if (cam >= 0) {
        problem.observations.push_back({cam, idx, problem.K.project(o.xy)});
        ++seen;
      }
    }
    problem.points.back().fixed =
        seen < 2 || (l->revived && config_.reuse_fix_revived) || (localization_only_ && !keyframe_window);
    return idx;
  };
  if (keyframe_window) {
    std::unordered_set<std::uint64_t> added;
    for (int k = 0; k < num_kf; ++k) {
      if (!free_kf[k]) continue;
      for (const auto& obs : kfs[k].observations) {
        const map::Landmark* l = map.landmark(obs.first);
        if (l && added.insert(obs.first).second) add_point(l, 0);
      }
    }
  } else {
    for (std::size_t i = 0; i < frame->tracks.size(); ++i) {
      const map::Landmark* l = map.landmark(frame->tracks[i].id);
      if (!l) continue;
      const int p = add_point(l, 1);
      problem.observations.push_back({current_cam, p, problem.K.project(frame->tracks[i].xy)});
    }
  }
  FrameRefinement out;
  out.T_w_c = T_w_c;
  if (problem.points.empty()) return out;
  optimization::BaOptions options = config_.ba;
  options.max_sweeps = keyframe_window ? config_.ba_keyframe_sweeps : config_.ba_frame_sweeps;
  options.compute_covariance = !keyframe_window;  // the frame's pose covariance (FrameResult)
  const optimization::BaSummary summary = optimization::solveSubspaceGaussNewton(problem, options);
  if (current_cam >= 0 && static_cast<std::size_t>(current_cam) < summary.camera_covariance_valid.size()) {
    out.covariance = summary.camera_covariance[current_cam];
    out.covariance_valid = summary.camera_covariance_valid[current_cam];
  }

  // What changed (only finite results).
  MapUpdate& u = out.update;
  for (std::size_t k = 0; k < kfs.size(); ++k) {
    const optimization::BaCamera& c = problem.cameras[k];
    if (!c.fixed && c.T_w_c.matrix().allFinite()) u.keyframe_poses.emplace_back(k, c.T_w_c);
  }
  if (current_cam >= 0 && problem.cameras[current_cam].T_w_c.matrix().allFinite()) {
    out.T_w_c = problem.cameras[current_cam].T_w_c;
  }
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!problem.points[i].fixed && problem.points[i].p_w.allFinite()) {
      u.positions.emplace_back(points[i]->id, problem.points[i].p_w);
    }
  }
  // Observations far off after the optimization mark their points; repeated
  // offenders leave the map and their tracks are dropped.
  std::vector<bool> bad(points.size(), false);
  for (std::size_t o = 0; o < problem.observations.size() && o < summary.residual_px.size(); ++o) {
    if (summary.residual_px[o] > config_.max_reprojection_px) bad[problem.observations[o].point] = true;
  }
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (bad[i]) u.offenders.push_back(points[i]->id);
  }
  return out;
}

KeyframeDecision Mapper::needKeyframe(const FrameContext& frame, const Eigen::Isometry3d& T_w_c,
                                      const map::Map& map) const {
  KeyframeDecision d;
  d.needed = true;
  if (map.keyframes().empty()) return d;
  const map::Keyframe& kf = map.keyframes().back();
  const Eigen::Matrix3d R_cur_kf = (T_w_c.inverse() * kf.T_w_c).rotation();
  std::vector<double> parallax;
  std::size_t mapped = 0;
  for (std::size_t i = 0; i < frame.tracks.size(); ++i) {
    const FrameTrack& t = frame.tracks[i];
    if (map.landmark(t.id)) ++mapped;
    auto it = kf.observations.find(t.id);
    if (it == kf.observations.end()) continue;
    const Eigen::Vector3d f = R_cur_kf * it->second.homogeneous();
    if (f.z() <= 1e-9) continue;
    parallax.push_back((f.hnormalized() - t.xy).norm() * camera_.fx());
  }
  const double med = upperMedian(parallax);
  d.parallax_px = med;
  if (med >= config_.keyframe_parallax_px) return d;
  const double mapped_ratio =
      frame.tracks.empty() ? 0.0 : static_cast<double>(mapped) / static_cast<double>(frame.tracks.size());
  d.needed = mapped_ratio < config_.keyframe_min_mapped_ratio && med >= 0.3 * config_.keyframe_parallax_px;
  return d;
}

TriangulationBacklog Mapper::backlog(const FrameContext& frame, const Eigen::Isometry3d& T_w_c,
                                     const map::Map& map) const {
  TriangulationBacklog b;
  const auto& kfs = map.keyframes();
  if (kfs.empty()) return b;
  const Eigen::Matrix3d R_w_c = T_w_c.rotation();
  std::vector<double> parallax;
  for (const FrameTrack& t : frame.tracks) {
    if (map.landmark(t.id)) continue;
    // A keyframe takes every track of its frame, so a track is seen by the
    // keyframes from its detection on: start at the first keyframe not older
    // than that (they are ordered by frame) instead of asking every keyframe.
    // (Observations a track inherited with a reused map point, Map::relabelLandmark,
    // sit in older keyframes and are not counted: this is the track's own parallax.)
    const std::uint64_t born = frame.frame_index - std::min<std::uint64_t>(t.age, frame.frame_index);
    auto k = std::lower_bound(kfs.begin(), kfs.end(), born,
                              [](const map::Keyframe& kf, std::uint64_t f) { return kf.frame_index < f; });
    const Eigen::Vector2d* oldest_xy = nullptr;
    for (; k != kfs.end() && k->frame_index < frame.frame_index; ++k) {
      auto it = k->observations.find(t.id);
      if (it == k->observations.end()) continue;
      oldest_xy = &it->second;
      break;
    }
    if (!oldest_xy) continue;  // born after the last keyframe older than this frame
    ++b.candidates;
    const auto later = std::next(k);
    if (later != kfs.end() && kfs.back().observations.count(t.id)) ++b.seen_twice;
    // The angle between the two viewing rays in the world frame is the
    // parallax the point would be triangulated with now (no depth needed).
    const Eigen::Vector3d a = k->T_w_c.rotation() * oldest_xy->homogeneous();
    const Eigen::Vector3d c = R_w_c * t.xy.homogeneous();
    parallax.push_back(std::atan2(a.cross(c).norm(), a.dot(c)) * 180.0 / M_PI);
  }
  b.median_parallax_deg = parallax.empty() ? 0.0 : upperMedian(parallax);
  return b;
}

map::Keyframe Mapper::keyframeOf(const FrameContext& frame, const Eigen::Isometry3d& T_w_c) {
  map::Keyframe kf;
  kf.frame_index = frame.frame_index;
  kf.timestamp = frame.timestamp;
  kf.T_w_c = T_w_c;
  for (const FrameTrack& t : frame.tracks) kf.observations.emplace(t.id, t.xy);
  return kf;
}

Triangulation Mapper::triangulate(const FrameContext& frame, const map::Map& map) const {
  const auto& kfs = map.keyframes();
  Triangulation out;
  std::vector<Eigen::Isometry3d> poses;
  std::vector<Eigen::Vector2d> obs;
  for (const FrameTrack& t : frame.tracks) {
    if (map.landmark(t.id)) continue;
    poses.clear();
    obs.clear();
    for (const map::Keyframe& kf : kfs) {
      auto it = kf.observations.find(t.id);
      if (it == kf.observations.end()) continue;
      poses.push_back(kf.T_w_c);
      obs.push_back(it->second);
    }
    if (poses.size() < 2) continue;
    geometry::TriangulationResult tr = geometry::triangulatePoint(poses, obs, config_.triangulation);
    if (!tr.ok) {
      ++out.rejected_by[rejectionName(tr.failed)];
      continue;
    }
    map::NewLandmark l;
    l.id = t.id;
    l.p_w = tr.p_w;
    l.intensity = t.intensity;
    l.polarity = t.polarity;
    l.seen_frame = frame.frame_index;
    out.landmarks.push_back(l);
  }
  return out;
}

}  // namespace vitamin_e::pipeline
