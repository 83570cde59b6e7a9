#pragma once
// The tracking stage: image -> TrackedFrame (dense curvature-extrema tracks,
// undistorted). Owns the tracker and the stream's stamp order. The mapping
// stage may run on another thread: its only way back is dropTracks(), which
// takes effect at a frame fixed by the call order, never by the threads' timing.
#include <cstdint>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

#include "vitamin_e/camera/camera.h"
#include "vitamin_e/pipeline/tracked_frame.h"
#include "vitamin_e/tracking/dense_tracker.h"

namespace vitamin_e::pipeline {

// Throws std::invalid_argument unless image is a non-empty CV_8UC1 of the
// camera's size (the message names both sizes).
void validateImage(const cv::Mat& image, const camera::Camera& camera);

class FrontEnd {
 public:
  FrontEnd(const tracking::TrackerConfig& config, const camera::Camera& camera);

  // Tracks one image (validated: std::invalid_argument). A stamp that is not
  // finite or does not increase gives a skipped frame and leaves the tracker as it was.
  // priors: asked for by the tracker when it uses them (tracking::DenseTracker::track).
  // frames_in_mapping: how many of the frames just before this one the mapping stage may
  // still be on (0 sequential, 1 pipelined); their drops wait for the next frame.
  TrackedFrame track(const cv::Mat& image, double timestamp, const std::string& timestamp_text,
                     const tracking::DenseTracker::PriorProvider& priors = {}, std::uint64_t frames_in_mapping = 0);
  // Tracks the mapping stage rejected while it mapped the frame of TrackedFrame::sequence
  // `from_sequence`: they end before frame from_sequence + 1 + frames_in_mapping is tracked
  // (the caller makes sure that frame's mapping is over by then). Thread-safe.
  void dropTracks(const std::vector<std::uint64_t>& ids, std::uint64_t from_sequence);
  // Forgets every track and pending drop; the stamp order is kept.
  void reset();
  // reset(), and the stamp order starts over: the next frame may be older than the
  // last (the stream restarted: a bag replayed, a clock reset).
  void restart();
  // Frames and tracks continue the numbering of a map loaded from a file: the
  // next frame's index is at least next_frame_index (frame indices of this
  // stream are offset by the difference, see frameIndexOffset()) and new track
  // ids are at least next_track_id. Call before the first frame.
  void continueNumbering(std::uint64_t next_frame_index, std::uint64_t next_track_id);
  // Frame index of the first frame of this stream (0 unless continueNumbering).
  std::uint64_t frameIndexOffset() const { return frame_index_offset_; }
  const camera::Camera& camera() const { return camera_; }

 private:
  camera::Camera camera_;
  tracking::DenseTracker tracker_;
  std::uint64_t next_frame_index_ = 0;
  std::uint64_t frame_index_offset_ = 0;
  bool have_last_stamp_ = false;
  double last_stamp_ = 0.0;
  std::uint64_t calls_ = 0;  // track() calls so far (TrackedFrame::sequence)
  std::mutex drops_mutex_;
  std::vector<std::pair<std::uint64_t, std::uint64_t>> pending_drops_;  // (from_sequence, track id)
};

}  // namespace vitamin_e::pipeline
