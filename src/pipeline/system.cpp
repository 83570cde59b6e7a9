// pipeline::System: the stages composed, and the per-frame dispatch between
// them: initialization until there is a map, then pose, map reuse, per-frame BA
// and keyframes; relocalization after a loss. Stages read the map; what they
// change comes back as values that the steps here apply (applyUpdate, the
// keyframe and the first map), so the map is written only in this file.
#include "vitamin_e/pipeline/system.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "system_impl.h"

namespace vitamin_e::pipeline {

namespace {
// What the configuration leaves to the system: pixel thresholds of the geometry stages are
// converted with the camera's focal length; counts of points follow the tracker's point budget.
SystemConfig resolvedFor(SystemConfig config, const camera::Camera& camera) {
  const double focal = 0.5 * (camera.fx() + camera.fy());
  config.init.focal_px = focal;
  config.pnp.focal_px = focal;
  config.triangulation.focal_px = focal;
  const auto share_of_budget = [&config](double fraction, int floor) {
    return std::max(floor, static_cast<int>(std::lround(fraction * config.tracker.max_points)));
  };
  config.min_init_tracks = share_of_budget(config.min_init_track_budget_fraction, kMinInitTracksFloor);
  config.ground.plane.min_inliers = share_of_budget(config.ground.min_inlier_budget_fraction, kMinRoadInliersFloor);
  return config;
}

// The tracker's counts of the frame into its diagnostics; the tracks it ended, by id.
EndedTracks takeTrackerCounts(TrackedFrame* f, FrameResult* result) {
  result->timing_ms["tracking"] = f->tracking_ms;
  FrameDiagnostics& d = result->diagnostics;
  d.tracks_born = f->tracks_born;
  d.tracks_lost = f->tracks_lost;
  d.tracks_dropped = f->tracks_dropped;
  d.tracks_from_prior = f->tracks_from_prior;
  d.lost_by = std::move(f->lost_by);
  EndedTracks ended = std::move(f->ended);
  std::sort(ended.begin(), ended.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  return ended;
}

FrameContext contextOf(TrackedFrame&& f) {
  FrameContext frame;
  frame.frame_index = f.frame_index;
  frame.timestamp = f.timestamp;
  frame.timestamp_text = std::move(f.timestamp_text);
  frame.tracks = std::move(f.tracks);
  frame.image = std::move(f.image);
  return frame;
}
}  // namespace

System::Impl::Impl(const SystemConfig& cfg, const camera::Camera& cam)
    : config(resolvedFor(cfg, cam)),
      camera(cam),
      front_end(cfg.tracker, cam),
      initializer(config, cam.fx()),
      localizer(config),
      reuse(config, cam),
      mapper(config, cam),
      relocalizer(config.relocalization, cam, config.pnp),
      ground(config.ground),
      recovery({config.relocalization.max_frames, config.min_init_tracks}),
      map(cfg.map) {}

TrackedFrame System::Impl::trackFrame(const cv::Mat& image, double timestamp, const std::string& timestamp_text,
                                      const std::function<void()>& before_priors, std::uint64_t frames_in_mapping) {
  const auto priors = [&]() {
    if (before_priors) before_priors();
    std::shared_ptr<const TrackPriorSource> source;
    {
      std::lock_guard<std::mutex> lock(prior_mutex);
      source = frames_in_mapping > 0 ? counted_prior_source : prior_source;
    }
    return source ? predictTrackPositions(*source, camera, timestamp) : std::vector<tracking::TrackPrior>{};
  };
  TrackedFrame f = front_end.track(image, timestamp, timestamp_text, priors, frames_in_mapping);
  if (!f.skipped) timings.add("tracking", f.tracking_ms);
  return f;
}

FrameResult System::Impl::mapFrame(TrackedFrame&& f, const PoseListener& on_pose) {
  FrameResult result;
  result.timestamp = f.timestamp;
  result.frame_index = f.frame_index - front_end.frameIndexOffset();  // this stream's own count
  result.init_retries = counters.init_retries;
  result.relocalizations = counters.relocalizations;
  priors_out_early = false;  // a frame before that threw after its early priors: counted once
  if (f.skipped) {
    setOutcome(recovery.apply(RecoveryEvent::kSkipped, {}), &result);
    result.message = std::move(f.message);
    markPriorsOut();
    return result;
  }
  const double tracking_ms = f.tracking_ms;
  mapping_sequence = f.sequence;
  mapper_behind = f.mapper_behind;
  priors_awaited = f.priors_awaited;
  const EndedTracks ended = takeTrackerCounts(&f, &result);
  FrameContext frame = contextOf(std::move(f));

  const auto t_start = TimingClock::now();
  switch (recovery.state()) {
    case TrackingState::kTracking: track(frame, ended, on_pose, &result); break;
    case TrackingState::kRelocalizing: relocalize(frame, &result); break;
    default: initialize(frame, &result);
  }
  describeFrame(frame, &result);
  publishPriorSource(result);
  markPriorsOut();
  // total = the work of both stages for this frame (tracking + mapping).
  const double total = tracking_ms + elapsedMs(t_start);
  timings.add("total", total);
  result.timing_ms["total"] = total;
  ++counters.frames_processed;
  return result;
}

void System::Impl::publishEarlyPriors(const FrameContext& frame) {
  // Only for a tracker that waits for them: otherwise the frame's end puts them out once.
  if (!config.tracker.retry_from_prior || !priors_awaited) return;
  std::vector<std::uint64_t> ids;
  ids.reserve(frame.tracks.size());
  for (const FrameTrack& t : frame.tracks) ids.push_back(t.id);
  setPriorSource(priorSourceOf(ids));
  markPriorsOut();
  priors_out_early = true;
}

void System::Impl::markPriorsOut() {
  if (priors_out_early) {
    priors_out_early = false;  // the end of the frame that published early: counted already
    return;
  }
  {
    std::lock_guard<std::mutex> lock(prior_mutex);
    ++prior_frames;
    counted_prior_source = prior_source;
  }
  prior_cv.notify_all();
}

void System::Impl::clearPriorSource() {
  std::lock_guard<std::mutex> lock(prior_mutex);
  prior_source.reset();
  counted_prior_source.reset();
}

void System::Impl::setPriorSource(std::shared_ptr<const TrackPriorSource> source) {
  std::lock_guard<std::mutex> lock(prior_mutex);
  prior_source = std::move(source);
}

std::shared_ptr<const TrackPriorSource> System::Impl::priorSourceOf(const std::vector<std::uint64_t>& ids) const {
  auto source = std::make_shared<TrackPriorSource>();
  source->motion = motion;
  source->p_w_by_track.reserve(ids.size());
  for (std::uint64_t id : ids) {
    if (const map::Landmark* l = map.landmark(id)) source->p_w_by_track.emplace_back(id, l->p_w);
  }
  return source;
}

// The tracker's priors for the next frame come from this frame's map tracks
// and motion (tracker.retry_from_prior); none while the camera is not tracked.
void System::Impl::publishPriorSource(const FrameResult& result) {
  const bool tracking = result.pose_valid && motion.valid() && recovery.state() == TrackingState::kTracking;
  setPriorSource(tracking && config.tracker.retry_from_prior ? priorSourceOf(prev_mapped_ids) : nullptr);
}

void System::Impl::describeFrame(const FrameContext& frame, FrameResult* result) {
  result->points.reserve(frame.tracks.size());
  std::size_t mapped = 0;
  prev_mapped_ids.clear();
  for (const FrameTrack& t : frame.tracks) {
    FramePoint p;
    p.track_id = t.id;
    p.uv = t.uv;
    p.intensity = t.intensity;
    if (const map::Landmark* l = map.landmark(t.id)) {
      p.has_position = true;
      p.p_w = l->p_w;
      ++mapped;
      if (result->pose_valid) prev_mapped_ids.push_back(t.id);
    }
    result->points.push_back(p);
  }
  if (!std::is_sorted(prev_mapped_ids.begin(), prev_mapped_ids.end())) {
    std::sort(prev_mapped_ids.begin(), prev_mapped_ids.end());
  }
  FrameDiagnostics& d = result->diagnostics;
  d.keyframes = map.keyframes().size();
  if (result->pose_valid) {
    const TriangulationBacklog b = mapper.backlog(frame, result->T_w_c, map);
    d.candidates = b.candidates;
    d.candidates_two_keyframes = b.seen_twice;
    d.candidate_parallax_deg = b.median_parallax_deg;
  }
  result->num_mapped = mapped;
  result->num_tracked = frame.tracks.size();
  result->map_size = map.landmarks().size();
  result->init_retries = counters.init_retries;
  result->relocalizations = counters.relocalizations;
}

void System::Impl::recordPose(double t, const std::string& text, const Eigen::Isometry3d& T_w_c) {
  if (!T_w_c.matrix().allFinite()) return;
  TrajectoryEntry e;
  e.timestamp = t;
  e.timestamp_text = text;
  e.T_w_c = T_w_c;
  trajectory.push_back(e);
  ++counters.frames_tracked;
  if (counters.first_init_frame < 0) ++counters.localized_before_init;  // the reference and in-between frames
}

AppliedMapUpdate System::Impl::applyUpdate(const MapUpdate& update) {
  OffencePolicy policy;
  policy.max_outlier_count = config.max_outlier_count;
  policy.localization_only = localization_only;
  AppliedMapUpdate applied = applyMapUpdate(update, policy, &map);
  front_end.dropTracks(applied.removed, mapping_sequence);  // their tracks end before the next image is tracked
  counters.reused_map_points += static_cast<std::uint64_t>(applied.reassociated);
  return applied;
}

void System::Impl::markTracksSeen(const FrameContext& frame) {
  for (const FrameTrack& t : frame.tracks) map.markSeen(t.id, frame.frame_index);
}

int System::Impl::reuseMapPoints(const FrameContext& frame, const Eigen::Isometry3d& T_w_c, bool all_dormant) {
  MapUpdate u;
  u.reassociations = reuse.associate(frame, T_w_c, scene_depth, map, all_dormant);
  return applyUpdate(u).reassociated;
}

void System::Impl::penalize(const std::vector<std::uint64_t>& outliers) {
  MapUpdate u;
  u.offenders = outliers;
  applyUpdate(u);
}

FrameRefinement System::Impl::refine(const FrameContext& frame, const Eigen::Isometry3d& T_w_c) {
  FrameRefinement refined = mapper.refineFrame(frame, T_w_c, map);
  applyUpdate(refined.update);
  return refined;
}

void System::Impl::initialize(FrameContext& frame, FrameResult* result) {
  ScopedTimer timer(&timings, "init", &result->timing_ms);
  if (localization_only) {  // a new map would be a change of the map
    report(RecoveryEvent::kNoMapYet, frame, result);
    result->message = "localization only: no map to localize in";
    return;
  }
  // The first map defines the world (first reference camera = origin); after a
  // loss, the new map continues from the last known pose at the last scale.
  MapAnchor anchor;
  if (initialized_once && motion.valid()) {
    anchor.T_w_ref = motion.lastPose();
    anchor.scale = scene_depth;
  }
  InitAttempt attempt = initializer.addFrame(frame, anchor);
  if (!attempt.initialized) {
    report(RecoveryEvent::kNoMapYet, frame, result);
    result->message = std::move(attempt.message);
    return;
  }
  InitialMap& m = attempt.map;
  FrameDiagnostics& d = result->diagnostics;
  d.keyframe = true;
  d.triangulated = static_cast<int>(m.landmarks.size());
  d.init_from_homography = m.from_homography;
  d.init_ambiguous = m.ambiguous;
  startMap(&m, frame);
  const Eigen::Isometry3d T_w_c = localizeInitialFrames(m, frame);
  relocalizer.addKeyframe(frame.image, frame, map, T_w_c);
  report(RecoveryEvent::kMapBuilt, frame, result);
  result->pose_valid = true;
  result->T_w_c = T_w_c;
  result->message = "initialized: " + std::to_string(map.landmarks().size()) + " points, parallax " +
                    std::to_string(m.parallax_deg) + " deg" + m.notes;
}

void System::Impl::startMap(InitialMap* m, const FrameContext& frame) {
  map.clear();
  ground.reset();  // a new map, a new scale
  for (const map::NewLandmark& l : m->landmarks) map.addLandmark(l);
  map.addKeyframe(std::move(m->reference));
  map.addKeyframe(std::move(m->current));
  map.markAllSeen(frame.frame_index);
  applyUpdate(mapper.optimizeWindow(map));
}

Eigen::Isometry3d System::Impl::localizeInitialFrames(const InitialMap& m, const FrameContext& frame) {
  // The reference frame and the frames in between, localized against the new map.
  Eigen::Isometry3d guess = map.keyframes().front().T_w_c;
  recordPose(m.reference_frame.timestamp, m.reference_frame.timestamp_text, guess);
  for (const PendingFrame& f : m.between) {
    const PoseEstimate e = localizer.estimate(map, f.xy, guess);
    if (!e.ok) continue;
    recordPose(f.timestamp, f.timestamp_text, e.T_w_c);
    guess = e.T_w_c;
  }
  Eigen::Isometry3d T_w_c = map.keyframes().back().T_w_c;
  if (counters.first_init_frame < 0) counters.first_init_frame = static_cast<long long>(frame.frame_index);
  recordPose(frame.timestamp, frame.timestamp_text, T_w_c);
  // Motion model from the last localized in-between frame, if any.
  Eigen::Isometry3d T_prev_cur = Eigen::Isometry3d::Identity();
  double interval = std::nan("");
  if (trajectory.size() >= 2) {
    T_prev_cur = trajectory[trajectory.size() - 2].T_w_c.inverse() * T_w_c;
    interval = frame.timestamp - trajectory[trajectory.size() - 2].timestamp;
  }
  motion.restart(T_w_c, T_prev_cur, frame.timestamp, interval);
  initialized_once = true;
  return T_w_c;
}

Transition System::Impl::report(RecoveryEvent event, const FrameContext& frame, FrameResult* result) {
  RecoveryFacts facts;
  facts.index_available = config.relocalization.enabled && relocalizer.size() > 0;
  facts.keep_map = keepRelocalizing();
  facts.frame_tracks = frame.tracks.size();
  const Transition t = recovery.apply(event, facts);
  setOutcome(t, result);
  if (t.action == RecoveryAction::kNewMap || t.action == RecoveryAction::kNewMapFromFrame) {
    ++counters.init_retries;
    map.clear();
    relocalizer.clear();  // the new map has its own scale: the old keyframes do not fit it
    initializer.reset();
    if (t.action == RecoveryAction::kNewMapFromFrame) initializer.restartFrom(frame);
  }
  return t;
}

void System::Impl::setOutcome(const Transition& t, FrameResult* result) {
  result->state = t.frame_state;
  result->reason = t.reason;
}

// Tracking failed at this frame: the camera is looked for in the map (this
// frame at once, if Recovery says so), or a new map starts.
void System::Impl::lose(FrameContext& frame, RecoveryEvent event, const std::string& why, FrameResult* result) {
  const Transition t = report(event, frame, result);
  const std::string lost = "lost: " + why;
  if (t.action == RecoveryAction::kRelocalizeNow) {
    const MapSearch search = searchMap(frame, result);
    if (search.found) {
      report(RecoveryEvent::kRelocalized, frame, result);
      result->message = lost + "; " + search.message;
      return;
    }
  }
  result->message = lost + (t.state == TrackingState::kRelocalizing ? "; relocalizing" : "; re-initializing");
}

void System::Impl::relocalize(FrameContext& frame, FrameResult* result) {
  const MapSearch search = searchMap(frame, result);
  const Transition t =
      report(search.found ? RecoveryEvent::kRelocalized : RecoveryEvent::kNotRelocalized, frame, result);
  if (t.reason == StateReason::kRelocalizationTimedOut) {
    result->message = "lost: not relocalized in " + std::to_string(recovery.lostFrames()) + " frames; re-initializing";
  } else {
    result->message = (search.found ? "" : "relocalizing: ") + search.message;
  }
}

System::Impl::MapSearch System::Impl::searchMap(FrameContext& frame, FrameResult* result) {
  ScopedTimer timer(&timings, "relocalize", &result->timing_ms);
  const Relocalization r = relocalizer.relocalize(frame.image, frame, map);
  FrameDiagnostics& d = result->diagnostics;
  d.relocalization_matches = r.matches;
  d.relocalization_inliers = r.inliers;
  d.relocalization = r.ok ? RelocalizationOutcome::kDidNotHold : RelocalizationOutcome::kNotFound;
  if (!r.ok || !resume(frame, r.T_w_c, result)) return {false, r.ok ? "the pose found did not hold" : r.why};
  d.relocalization = RelocalizationOutcome::kRelocalized;
  ++counters.relocalizations;
  return {true, "relocalized against keyframe " + std::to_string(r.keyframe) + " (" + std::to_string(r.inliers) +
                    " of " + std::to_string(r.matches) + " matches" +
                    (r.quarter_turns == 2 ? ", camera upside down" : "") + ")"};
}

// Continues tracking from a relocalized pose: map points are handed to the
// frame's tracks around it, the pose is estimated and refined with them, and
// the frame becomes a keyframe so that new points are triangulated from it.
bool System::Impl::resume(FrameContext& frame, const Eigen::Isometry3d& T_w_guess, FrameResult* result) {
  FrameDiagnostics& d = result->diagnostics;
  d.reused = reuseMapPoints(frame, T_w_guess, true);
  const PoseEstimate pose = localizer.estimate(frame, map, T_w_guess);
  d.pose_points = pose.num_points;
  d.pose_inliers = pose.num_inliers;
  if (!pose.ok) return false;
  penalize(pose.outliers);
  d.reused += reuseMapPoints(frame, pose.T_w_c, true);
  const FrameRefinement refined = refine(frame, pose.T_w_c);
  Eigen::Isometry3d T_w_c = refined.T_w_c;
  if (!T_w_c.matrix().allFinite()) return false;
  result->T_w_c_covariance = refined.covariance;
  result->T_w_c_covariance_valid = refined.covariance_valid;
  markTracksSeen(frame);
  recordPose(frame.timestamp, frame.timestamp_text, T_w_c);
  motion.restart(T_w_c, Eigen::Isometry3d::Identity(), frame.timestamp);
  if (!localization_only) T_w_c = insertKeyframe(frame, T_w_c, &d);
  result->pose_valid = true;
  result->T_w_c = T_w_c;
  return true;
}

void System::Impl::track(FrameContext& frame, const EndedTracks& ended, const PoseListener& on_pose,
                         FrameResult* result) {
  markTracksSeen(frame);
  const PoseEstimate pose = estimatePose(frame, ended, result);
  if (!pose.ok) {
    lose(frame, RecoveryEvent::kPoseFailed, pose.why, result);
    return;
  }
  Eigen::Isometry3d T_w_c = refineTrackedPose(frame, pose.T_w_c, result);
  // A pose must be finite and must not jump: a step far beyond the scene depth
  // is a failure, not motion (after dropped frames: per frame interval).
  const double step = (T_w_c.translation() - motion.lastPose().translation()).norm();
  const double max_step = config.max_step_depth_ratio * scene_depth * std::max(1.0, motion.stepRatio(frame.timestamp));
  if (!T_w_c.matrix().allFinite() || step > max_step) {
    lose(frame, RecoveryEvent::kPoseJumped,
         "pose jumped by " + std::to_string(step) + " (scene depth " + std::to_string(scene_depth) + ")", result);
    return;
  }
  recordPose(frame.timestamp, frame.timestamp_text, T_w_c);
  motion.update(T_w_c, frame.timestamp);
  publishEarlyPriors(frame);
  KeyframeDecision decision = localization_only ? KeyframeDecision{} : mapper.needKeyframe(frame, T_w_c, map);
  if (pose.weak_kept && !config.keyframe_on_weak_pose) decision.needed = false;
  if (on_pose) {
    // The result so far holds the pose's covariance; the pose and the keyframe flag are these.
    FramePose pose = poseOf(*result);
    pose.T_w_c = T_w_c;
    pose.keyframe = decision.needed;
    on_pose(pose);
  }
  {
    ScopedTimer timer(&timings, "map", &result->timing_ms);
    T_w_c = extendMap(frame, T_w_c, decision, &result->diagnostics);
  }
  report(RecoveryEvent::kPoseFound, frame, result);
  result->pose_valid = true;
  result->T_w_c = T_w_c;
}

Eigen::Isometry3d System::Impl::refineTrackedPose(const FrameContext& frame, const Eigen::Isometry3d& T_w_c,
                                                  FrameResult* result) {
  {
    // Localized: new tracks where old map points project take them over.
    ScopedTimer timer(&timings, "reuse", &result->timing_ms);
    result->diagnostics.reused = reuseMapPoints(frame, T_w_c, false);
  }
  ScopedTimer timer(&timings, "ba", &result->timing_ms);
  const FrameRefinement refined = refine(frame, T_w_c);
  result->T_w_c_covariance = refined.covariance;
  result->T_w_c_covariance_valid = refined.covariance_valid;
  return refined.T_w_c;
}

PoseEstimate System::Impl::estimatePose(const FrameContext& frame, const EndedTracks& ended, FrameResult* result) {
  ScopedTimer timer(&timings, "pose", &result->timing_ms);
  FrameDiagnostics& d = result->diagnostics;
  const std::vector<std::uint64_t> ended_map_tracks = countSurvivingMapTracks(frame, &d);
  // The weak-pose exception below trusts the motion model when the tracks survived but many
  // went wrong (blur). When far fewer of the last frame's map tracks survived than usually
  // do here (a cut, a whip turn), the survivors sit on nearby extrema and agree on a pose
  // near any prediction: no exception then.
  const bool collapsed = d.prev_map_points > 0 &&
                         track_survival.collapsed(d.prevMapTrackedFraction(), config.weak_pose_min_survival_ratio);
  // Accepted only when well constrained (enough inliers, and most of the
  // tracked map points agree): however many tracks a turn or a cut ended.
  const Eigen::Isometry3d predicted = motion.predict(frame.timestamp);  // across dropped frames too
  PoseEstimate pose = localizer.estimate(frame, map, predicted, collapsed ? nullptr : &motion.lastPose());
  if (!pose.ok && collapsed) {
    pose.why += "; " + std::to_string(d.prev_map_tracked) + " of the last frame's " +
                std::to_string(d.prev_map_points) + " map tracks survived (usually " +
                std::to_string(static_cast<int>(std::lround(100.0 * track_survival.usual()))) + " %)";
  }
  if (d.prev_map_points > 0) track_survival.add(d.prevMapTrackedFraction());
  d.pose_points = pose.num_points;
  d.pose_inliers = pose.num_inliers;
  // Where the ended map tracks went: judged at the new pose, or at the
  // motion model's prediction when there is none.
  diagnoseEndedMapTracks(ended_map_tracks, ended, pose.ok ? pose.T_w_c : predicted, &d);
  if (pose.ok) penalize(pose.outliers);
  if (pose.weak_kept) {
    result->message = "weak pose kept: " + std::to_string(pose.num_inliers) + " of " + std::to_string(pose.num_points) +
                      " tracked map points agree, the step is the predicted one";
  }
  return pose;
}

Eigen::Isometry3d System::Impl::extendMap(const FrameContext& frame, Eigen::Isometry3d T_w_c,
                                          const KeyframeDecision& decision, FrameDiagnostics* d) {
  d->keyframe_parallax_px = decision.parallax_px;
  if (decision.needed) {
    T_w_c = insertKeyframe(frame, T_w_c, d, mapper_behind);
    if (ground.enabled()) holdGroundScale(frame, T_w_c, d);
  }
  // Median depth of the mapped points in view: the map's scale at this place.
  std::vector<double> depths;
  const Eigen::Isometry3d T_c_w = T_w_c.inverse();
  for (const FrameTrack& t : frame.tracks) {
    if (const map::Landmark* l = map.landmark(t.id)) depths.push_back((T_c_w * l->p_w).z());
  }
  if (depths.size() > 20) scene_depth = std::max(1e-6, upperMedian(depths));
  return T_w_c;
}

Eigen::Isometry3d System::Impl::insertKeyframe(const FrameContext& frame, const Eigen::Isometry3d& T_w_c,
                                               FrameDiagnostics* d, bool may_defer) {
  map.addKeyframe(Mapper::keyframeOf(frame, T_w_c));
  Triangulation made = mapper.triangulate(frame, map);
  for (const map::NewLandmark& l : made.landmarks) map.addLandmark(l);
  d->keyframe = true;
  d->triangulated = static_cast<int>(made.landmarks.size());
  d->triangulation_rejected_by = std::move(made.rejected_by);
  // Behind the tracker, the mapper catches up by leaving this window BA to the next keyframe, whose
  // BA frees this one too (the frame's own BA has refined its pose already). With one free keyframe
  // (and no sharing rule) the next BA would not free it: then never.
  const bool next_frees_it = config.ba_free_keyframes >= 2 || config.ba_free_min_shared > 0.0;
  window_ba_deferred = config.defer_keyframe_ba && may_defer && next_frees_it && !window_ba_deferred;
  d->window_ba_deferred = window_ba_deferred;
  if (!window_ba_deferred) applyUpdate(mapper.optimizeWindow(map));
  // The window BA moved the new keyframe: the frame's pose is the keyframe's.
  Eigen::Isometry3d T_w_kf = map.keyframes().back().T_w_c;
  motion.correctLast(T_w_kf);
  if (!trajectory.empty()) trajectory.back().T_w_c = T_w_kf;
  relocalizer.addKeyframe(frame.image, frame, map, T_w_kf);
  return T_w_kf;
}

void System::Impl::holdGroundScale(const FrameContext& frame, const Eigen::Isometry3d& T_w_c, FrameDiagnostics* d) {
  std::vector<Eigen::Vector3d> points_c;
  points_c.reserve(frame.tracks.size());
  const Eigen::Isometry3d T_c_w = T_w_c.inverse();
  for (const FrameTrack& t : frame.tracks) {
    if (const map::Landmark* l = map.landmark(t.id)) points_c.push_back(T_c_w * l->p_w);
  }
  const ScaleCorrection c = ground.update(points_c, motion.lastStepLength());
  d->ground_height = c.measured ? c.height : 0.0;
  d->ground_inliers = c.inliers;
  d->scale_correction = c.factor;
  if (c.factor == 1.0) return;
  // A similarity about the camera centre: the BA's cost and this pose do not
  // change, the steps from here on are in the corrected scale.
  const Eigen::Vector3d centre = T_w_c.translation();
  map.rescale(centre, c.factor);
  relocalizer.rescale(centre, c.factor);
  motion.rescale(c.factor);
  scene_depth *= c.factor;
}

std::vector<std::uint64_t> System::Impl::countSurvivingMapTracks(const FrameContext& frame, FrameDiagnostics* d) const {
  // Both id lists sorted and walked together: cheaper than hashing the
  // thousands of tracks of every frame (the tracker keeps its tracks in id order).
  std::vector<std::uint64_t> now;
  now.reserve(frame.tracks.size());
  for (const FrameTrack& t : frame.tracks) now.push_back(t.id);
  if (!std::is_sorted(now.begin(), now.end())) std::sort(now.begin(), now.end());
  d->prev_map_points = prev_mapped_ids.size();
  std::vector<std::uint64_t> ended_ids;
  auto n = now.begin();
  for (std::uint64_t id : prev_mapped_ids) {
    while (n != now.end() && *n < id) ++n;
    if (n != now.end() && *n == id) {
      ++d->prev_map_tracked;
    } else {
      ended_ids.push_back(id);
    }
  }
  return ended_ids;
}

void System::Impl::diagnoseEndedMapTracks(const std::vector<std::uint64_t>& ended_ids, const EndedTracks& ended,
                                          const Eigen::Isometry3d& T_w_c, FrameDiagnostics* d) const {
  const Eigen::Isometry3d T_c_w = T_w_c.inverse();
  for (std::uint64_t id : ended_ids) {
    auto e = std::lower_bound(ended.begin(), ended.end(), id,
                              [](const EndedTracks::value_type& a, std::uint64_t b) { return a.first < b; });
    ++d->prev_map_lost_by[e != ended.end() && e->first == id ? e->second : "dropped"];
    const map::Landmark* l = map.landmark(id);
    if (!l) continue;  // removed as an outlier meanwhile
    const Eigen::Vector3d p_c = T_c_w * l->p_w;
    Eigen::Vector2d uv;
    // The tracker keeps border_px off the image edge: a point there has left its view.
    const bool inside = p_c.z() > 0.0 && camera.project(p_c, &uv) && camera.inImage(uv, config.tracker.border_px);
    ++(inside ? d->prev_map_lost_in_view : d->prev_map_left_view);
  }
}

void System::Impl::reset() {
  map_loaded = false;
  prev_mapped_ids.clear();
  track_survival.clear();
  map.clear();
  relocalizer.clear();
  initializer.reset();
  recovery.reset();
  front_end.reset();
  motion.invalidate();
  clearPriorSource();
}

bool System::Impl::restartTracking() {
  const bool relocalizable = (config.relocalization.enabled && relocalizer.size() > 0) || keepRelocalizing();
  if (map.landmarks().empty() || !relocalizable) return false;
  front_end.restart();
  prev_mapped_ids.clear();
  initializer.reset();
  motion.invalidate();
  clearPriorSource();
  recovery.startRelocalizing();
  return true;
}

System::System(const SystemConfig& config, const camera::Camera& camera) {
  if (!camera.valid()) throw std::invalid_argument("System: the camera calibration is not set");
  config.validate();
  impl_ = std::make_unique<Impl>(config, camera);
}

System::~System() = default;

FrameResult System::process(const cv::Mat& image, double timestamp, const std::string& timestamp_text,
                            const PoseListener& on_pose) {
  return impl_->mapFrame(impl_->trackFrame(image, timestamp, timestamp_text, {}, 0), on_pose);
}

std::uint64_t System::priorsOut() const {
  std::lock_guard<std::mutex> lock(impl_->prior_mutex);
  return impl_->prior_frames;
}

void System::waitForPriors(std::uint64_t n) {
  std::unique_lock<std::mutex> lock(impl_->prior_mutex);
  impl_->prior_cv.wait(lock, [&] { return impl_->prior_frames >= n; });
}

TrackedFrame System::trackFrame(const cv::Mat& image, double timestamp, const std::string& timestamp_text,
                                const std::function<void()>& before_priors, std::uint64_t frames_in_mapping) {
  return impl_->trackFrame(image, timestamp, timestamp_text, before_priors, frames_in_mapping);
}

FrameResult System::mapFrame(TrackedFrame&& frame, const PoseListener& on_pose) {
  return impl_->mapFrame(std::move(frame), on_pose);
}

void System::reset() { impl_->reset(); }

bool System::restartTracking() { return impl_->restartTracking(); }

const std::vector<TrajectoryEntry>& System::trajectory() const { return impl_->trajectory; }

std::vector<MapPoint3> System::mapPoints() const {
  std::vector<MapPoint3> out;
  out.reserve(impl_->map.landmarks().size() + impl_->map.archive().size());
  for (const auto& kv : impl_->map.landmarks()) out.push_back({kv.first, kv.second.p_w, kv.second.intensity});
  for (const auto& a : impl_->map.archive()) out.push_back({0, a.p_w, a.intensity});
  return out;
}

std::size_t System::framesProcessed() const { return impl_->counters.frames_processed; }
std::size_t System::framesTracked() const { return impl_->counters.frames_tracked; }
std::size_t System::reusedMapPoints() const { return impl_->counters.reused_map_points; }
std::size_t System::dormantMapPoints() const { return impl_->map.dormant().size(); }
long long System::firstInitFrame() const {
  const long long f = impl_->counters.first_init_frame;
  return f < 0 ? f : f - static_cast<long long>(impl_->front_end.frameIndexOffset());
}
std::size_t System::framesTrackedSinceInit() const {
  const RunCounters& c = impl_->counters;
  return c.first_init_frame < 0 ? 0 : c.frames_tracked - c.localized_before_init;
}
int System::initRetries() const { return impl_->counters.init_retries; }
int System::relocalizations() const { return impl_->counters.relocalizations; }
const StageTimings& System::timings() const { return impl_->timings; }
const SystemConfig& System::config() const { return impl_->config; }
const camera::Camera& System::camera() const { return impl_->camera; }

}  // namespace vitamin_e::pipeline
