// pipeline::System: the public API and the per-frame dispatch.
#include "vitamin_e/pipeline/system.h"

#include <cmath>
#include <stdexcept>

#include "system_impl.h"

namespace vitamin_e::pipeline {

namespace {
// Pixel thresholds of the geometry stages are converted with the camera's focal length.
SystemConfig withCameraFocal(SystemConfig config, const camera::Camera& camera) {
  const double focal = 0.5 * (camera.fx() + camera.fy());
  config.init.focal_px = focal;
  config.pnp.focal_px = focal;
  config.triangulation.focal_px = focal;
  return config;
}
}  // namespace

System::Impl::Impl(const SystemConfig& cfg, const camera::Camera& cam)
    : config(withCameraFocal(cfg, cam)), camera(cam), tracker(cfg.tracker), map(cfg.map) {}

void validateImage(const cv::Mat& image, const camera::Camera& camera) {
  if (image.empty() || image.type() != CV_8UC1) {
    throw std::invalid_argument("SLAM input: expected a non-empty 8-bit single-channel (mono8) image");
  }
  if (image.cols != camera.width() || image.rows != camera.height()) {
    throw std::invalid_argument("SLAM input: image is " + std::to_string(image.cols) + "x" +
                                std::to_string(image.rows) + " but the calibration is " +
                                std::to_string(camera.width()) + "x" + std::to_string(camera.height()));
  }
}

void System::Impl::addTiming(const std::string& stage, double ms) {
  std::lock_guard<std::mutex> lock(timings_mutex);
  timings.add(stage, ms);
}

void System::Impl::dropTracksLater(const std::vector<std::uint64_t>& ids) {
  std::lock_guard<std::mutex> lock(drops_mutex);
  pending_drops.insert(pending_drops.end(), ids.begin(), ids.end());
}

TrackedFrame System::Impl::trackStage(const cv::Mat& image, double timestamp, const std::string& timestamp_text) {
  validateImage(image, camera);
  TrackedFrame f;
  f.timestamp = timestamp;
  f.timestamp_text = timestamp_text;
  if (!std::isfinite(timestamp) || (have_last_stamp && timestamp <= last_stamp)) {
    f.skipped = true;
    f.frame_index = next_frame_index;
    f.message = "frame skipped: timestamp " + std::to_string(timestamp) + " does not follow the previous " +
                std::to_string(last_stamp);
    return f;
  }
  have_last_stamp = true;
  last_stamp = timestamp;
  f.frame_index = next_frame_index++;
  // Tracks the back end rejected since the last frame stop here (applied before
  // tracking, so the sequential and the pipelined modes see the same rule).
  {
    std::vector<std::uint64_t> drops;
    {
      std::lock_guard<std::mutex> lock(drops_mutex);
      drops.swap(pending_drops);
    }
    if (!drops.empty()) tracker.dropTracks(drops);
  }
  const auto t0 = std::chrono::steady_clock::now();
  tracking::TrackerFrame tf = tracker.track(image, timestamp);
  f.tracks.reserve(tf.points.size());
  for (const tracking::TrackedPoint& p : tf.points) {
    FrameTrack t;
    t.id = p.id;
    t.uv = p.uv;
    t.intensity = p.intensity;
    t.polarity = p.curvature >= 0.f ? 1 : -1;
    if (!camera.unprojectNormalized(p.uv.cast<double>(), &t.xy)) continue;
    f.tracks.push_back(t);
  }
  f.tracking_ms = elapsedMs(t0);
  addTiming("tracking", f.tracking_ms);
  return f;
}

FrameResult System::Impl::mapStage(TrackedFrame&& f) {
  FrameResult result;
  result.timestamp = f.timestamp;
  result.state = state;
  result.frame_index = f.frame_index;
  result.init_retries = init_retries;
  if (f.skipped) {
    result.message = std::move(f.message);
    return result;
  }
  frame_index = f.frame_index;
  cur_t = f.timestamp;
  cur_text = std::move(f.timestamp_text);
  cur_tracks = std::move(f.tracks);
  result.timing_ms["tracking"] = f.tracking_ms;

  const auto t_start = std::chrono::steady_clock::now();
  if (state == TrackingState::kTracking) {
    track(&result);
  } else {
    initialize(&result);
  }
  result.state = state == TrackingState::kTracking && !result.pose_valid ? TrackingState::kLost : result.state;
  fillResultPoints(&result);
  result.num_tracked = cur_tracks.size();
  result.map_size = map.landmarks().size();
  result.init_retries = init_retries;
  // total = the work of both stages for this frame (tracking + mapping).
  const double total = f.tracking_ms + elapsedMs(t_start);
  addTiming("total", total);
  result.timing_ms["total"] = total;
  ++frames_processed;
  return result;
}

FrameResult System::Impl::process(const cv::Mat& image, double timestamp, const std::string& timestamp_text) {
  return mapStage(trackStage(image, timestamp, timestamp_text));
}

void System::Impl::recordPose(std::uint64_t index, double t, const std::string& text, const Eigen::Isometry3d& T_w_c) {
  if (!T_w_c.matrix().allFinite()) return;
  TrajectoryEntry e;
  e.timestamp = t;
  e.timestamp_text = text;
  e.T_w_c = T_w_c;
  trajectory.push_back(e);
  ++frames_tracked;
  if (first_init_frame < 0) ++localized_before_init;  // the reference and in-between frames of the first map
  (void)index;
}

void System::Impl::fillResultPoints(FrameResult* result) const {
  result->points.clear();
  result->points.reserve(cur_tracks.size());
  std::size_t mapped = 0;
  for (const FrameTrack& t : cur_tracks) {
    FramePoint p;
    p.track_id = t.id;
    p.uv = t.uv;
    p.intensity = t.intensity;
    if (const map::Landmark* l = map.landmark(t.id)) {
      p.has_position = true;
      p.p_w = l->p_w;
      ++mapped;
    }
    result->points.push_back(p);
  }
  result->num_mapped = mapped;
}

void System::Impl::resetMap() {
  map.clear();
  mapped_last_frame = 0;
  pending.clear();
  frames_since_keyframe = 0;
  state = TrackingState::kInitializing;
}

System::System(const SystemConfig& config, const camera::Camera& camera) {
  if (!camera.valid()) throw std::invalid_argument("System: the camera calibration is not set");
  config.validate();
  impl_ = std::make_unique<Impl>(config, camera);
}

System::~System() = default;

FrameResult System::process(const cv::Mat& image, double timestamp, const std::string& timestamp_text) {
  return impl_->process(image, timestamp, timestamp_text);
}

void System::reset() {
  impl_->resetMap();
  impl_->tracker.reset();
  {
    std::lock_guard<std::mutex> lock(impl_->drops_mutex);
    impl_->pending_drops.clear();
  }
  impl_->have_last_pose = false;
}

const std::vector<TrajectoryEntry>& System::trajectory() const { return impl_->trajectory; }

std::vector<MapPoint3> System::mapPoints() const {
  std::vector<MapPoint3> out;
  out.reserve(impl_->map.landmarks().size() + impl_->map.archive().size());
  for (const auto& kv : impl_->map.landmarks()) out.push_back({kv.first, kv.second.p_w, kv.second.intensity});
  for (const auto& a : impl_->map.archive()) out.push_back({0, a.p_w, a.intensity});
  return out;
}

std::size_t System::framesProcessed() const { return impl_->frames_processed; }
std::size_t System::framesTracked() const { return impl_->frames_tracked; }
std::size_t System::reusedMapPoints() const { return impl_->reused_points; }
std::size_t System::dormantMapPoints() const { return impl_->map.dormant().size(); }
long long System::firstInitFrame() const { return impl_->first_init_frame; }
std::size_t System::framesTrackedSinceInit() const {
  return impl_->first_init_frame < 0 ? 0 : impl_->frames_tracked - impl_->localized_before_init;
}
int System::initRetries() const { return impl_->init_retries; }
const StageTimings& System::timings() const { return impl_->timings; }
const SystemConfig& System::config() const { return impl_->config; }
const camera::Camera& System::camera() const { return impl_->camera; }

}  // namespace vitamin_e::pipeline
