#include "vitamin_e/pipeline/initializer.h"

#include "vitamin_e/common/timing.h"
#include "vitamin_e/geometry/two_view.h"

namespace vitamin_e::pipeline {

namespace {
PendingFrame pendingFrame(const FrameContext& frame) {
  PendingFrame pf;
  pf.frame_index = frame.frame_index;
  pf.timestamp = frame.timestamp;
  pf.timestamp_text = frame.timestamp_text;
  for (const FrameTrack& t : frame.tracks) pf.xy.emplace(t.id, t.xy);
  return pf;
}
}  // namespace

Initializer::Initializer(const SystemConfig& config, double focal_px) : config_(config), focal_px_(focal_px) {}

void Initializer::restartFrom(const FrameContext& frame) {
  pending_.clear();
  pending_.push_back(pendingFrame(frame));
}

InitAttempt Initializer::addFrame(const FrameContext& frame, const MapAnchor& anchor) {
  InitAttempt out;
  if (pending_.empty()) {
    restartFrom(frame);
    out.message = "initializing: reference frame set";
    return out;
  }
  const PendingFrame& ref = pending_.front();
  std::vector<Eigen::Vector2d> xy0, xy1;
  std::vector<std::uint64_t> ids;
  std::vector<double> disparity;
  for (const FrameTrack& t : frame.tracks) {
    auto it = ref.xy.find(t.id);
    if (it == ref.xy.end()) continue;
    xy0.push_back(it->second);
    xy1.push_back(t.xy);
    ids.push_back(t.id);
    disparity.push_back((t.xy - it->second).norm() * focal_px_);
  }
  if (static_cast<int>(ids.size()) < config_.min_init_tracks) {
    out.message = "initializing: too few tracks survive from the reference frame (" + std::to_string(ids.size()) +
                  "); new reference";
    restartFrom(frame);
    return out;
  }
  pending_.push_back(pendingFrame(frame));
  while (static_cast<int>(pending_.size()) > config_.init_max_pending_frames) pending_.erase(pending_.begin() + 1);

  const double med_disp = upperMedian(disparity);
  if (med_disp < config_.init_min_disparity_px) {
    out.message = "initializing: waiting for parallax (median disparity " + std::to_string(med_disp) + " px)";
    return out;
  }
  geometry::TwoViewResult tv = geometry::initializeTwoView(xy0, xy1, config_.init);
  if (!tv.ok) {
    out.message = "initializing: " + tv.reason;
    if (pending_.size() >= static_cast<std::size_t>(config_.init_max_pending_frames)) {
      PendingFrame cur = pending_.back();
      pending_.clear();
      pending_.push_back(std::move(cur));
      out.message += "; new reference";
    }
    return out;
  }

  Eigen::Isometry3d T_c1_c0 = tv.T_c1_c0;
  T_c1_c0.translation() *= anchor.scale;
  const Eigen::Isometry3d& T_w_c0 = anchor.T_w_ref;
  InitialMap& m = out.map;
  m.reference.frame_index = ref.frame_index;
  m.reference.timestamp = ref.timestamp;
  m.reference.T_w_c = T_w_c0;
  m.current.frame_index = frame.frame_index;
  m.current.timestamp = frame.timestamp;
  m.current.T_w_c = T_w_c0 * T_c1_c0.inverse();
  std::unordered_map<std::uint64_t, const FrameTrack*> track_of;
  for (const FrameTrack& t : frame.tracks) track_of[t.id] = &t;
  for (std::size_t i = 0; i < ids.size(); ++i) {
    m.reference.observations.emplace(ids[i], xy0[i]);
    m.current.observations.emplace(ids[i], xy1[i]);
    if (i < tv.valid.size() && tv.valid[i]) {
      auto t = track_of.find(ids[i]);
      map::NewLandmark l;
      l.id = ids[i];
      l.p_w = T_w_c0 * (anchor.scale * tv.points_c0[i]);
      l.intensity = t == track_of.end() ? 0 : t->second->intensity;
      l.polarity = t == track_of.end() ? std::int8_t{0} : t->second->polarity;
      l.seen_frame = frame.frame_index;
      m.landmarks.push_back(l);
    }
  }
  // Tracks born after the reference: observed by the second keyframe only.
  for (const FrameTrack& t : frame.tracks) m.current.observations.emplace(t.id, t.xy);
  m.reference_frame = pending_.front();
  m.between.assign(pending_.begin() + 1, pending_.end() - 1);
  m.parallax_deg = tv.median_parallax_deg;
  m.from_homography = tv.used_homography;
  m.ambiguous = tv.ambiguous;
  // Planar scenes (two_view.h): say where the motion came from, and say so when two views
  // could not tell two different motions apart (the map may then be built on the wrong one).
  if (tv.used_homography) {
    m.notes += "; planar scene: motion from the homography, not the essential matrix (best different motion: " +
               std::to_string(tv.num_rival_inliers) + " points in front of both cameras)";
  }
  if (tv.ambiguous) {
    m.notes += "; WARNING: ambiguous initialization, planar scene: another motion explains the views as well (" +
               std::to_string(tv.num_rival_inliers) + " of " + std::to_string(tv.num_inliers) + " points)";
  }
  pending_.clear();
  out.initialized = true;
  return out;
}

}  // namespace vitamin_e::pipeline
