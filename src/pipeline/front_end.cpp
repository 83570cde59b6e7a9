#include "vitamin_e/pipeline/front_end.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include "vitamin_e/common/timing.h"

namespace vitamin_e::pipeline {

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

FrontEnd::FrontEnd(const tracking::TrackerConfig& config, const camera::Camera& camera)
    : camera_(camera), tracker_(config) {}

TrackedFrame FrontEnd::track(const cv::Mat& image, double timestamp, const std::string& timestamp_text,
                             const tracking::DenseTracker::PriorProvider& priors, std::uint64_t frames_in_mapping) {
  const std::uint64_t sequence = calls_++;
  validateImage(image, camera_);
  TrackedFrame f;
  f.sequence = sequence;
  f.timestamp = timestamp;
  f.timestamp_text = timestamp_text;
  if (!std::isfinite(timestamp) || (have_last_stamp_ && timestamp <= last_stamp_)) {
    f.skipped = true;
    f.frame_index = next_frame_index_;
    f.message = "frame skipped: timestamp " + std::to_string(timestamp) + " does not follow the previous " +
                std::to_string(last_stamp_);
    return f;
  }
  have_last_stamp_ = true;
  last_stamp_ = timestamp;
  f.frame_index = next_frame_index_++;
  f.image = image;
  {
    // The drops of the frames whose mapping is over; a later frame's stay pending.
    std::vector<std::uint64_t> drops;
    {
      std::lock_guard<std::mutex> lock(drops_mutex_);
      const auto due = [&](const std::pair<std::uint64_t, std::uint64_t>& d) {
        return d.first + 1 + frames_in_mapping <= sequence;
      };
      for (const auto& d : pending_drops_) {
        if (due(d)) drops.push_back(d.second);
      }
      pending_drops_.erase(std::remove_if(pending_drops_.begin(), pending_drops_.end(), due), pending_drops_.end());
    }
    if (!drops.empty()) f.tracks_dropped = static_cast<int>(tracker_.dropTracks(drops));
  }
  const auto t0 = std::chrono::steady_clock::now();
  tracking::TrackerFrame tf = tracker_.track(image, timestamp, priors);
  f.tracks.reserve(tf.points.size());
  for (const tracking::TrackedPoint& p : tf.points) {
    FrameTrack t;
    t.id = p.id;
    t.uv = p.uv;
    t.intensity = p.intensity;
    t.polarity = p.curvature >= 0.f ? 1 : -1;
    t.age = p.age;
    if (!camera_.unprojectNormalized(p.uv.cast<double>(), &t.xy)) continue;
    f.tracks.push_back(t);
  }
  f.tracks_born = tf.num_new;
  f.tracks_lost = tf.num_lost;
  f.tracks_from_prior = tf.num_from_prior;
  f.lost_by = std::move(tf.lost_by);
  f.ended = std::move(tf.ended);
  f.tracking_ms = elapsedMs(t0);
  return f;
}

void FrontEnd::dropTracks(const std::vector<std::uint64_t>& ids, std::uint64_t from_sequence) {
  if (ids.empty()) return;
  std::lock_guard<std::mutex> lock(drops_mutex_);
  for (std::uint64_t id : ids) pending_drops_.emplace_back(from_sequence, id);
}

void FrontEnd::continueNumbering(std::uint64_t next_frame_index, std::uint64_t next_track_id) {
  if (next_frame_index > next_frame_index_) {
    frame_index_offset_ += next_frame_index - next_frame_index_;
    next_frame_index_ = next_frame_index;
  }
  tracker_.reserveIdsBelow(next_track_id);
}

void FrontEnd::reset() {
  tracker_.reset();
  std::lock_guard<std::mutex> lock(drops_mutex_);
  pending_drops_.clear();
}

void FrontEnd::restart() {
  reset();
  have_last_stamp_ = false;
}

}  // namespace vitamin_e::pipeline
