#pragma once
// The level and summary of the tracking nodelet's /diagnostics status, from its statistics
// (a pure function, unit-tested). Levels are diagnostic_msgs::DiagnosticStatus's.
#include <cstddef>
#include <string>

namespace vitamin_e_ros {

struct HealthInput {
  bool calibrated = false;
  std::size_t received = 0;        // images received so far
  double since_input_s = 1e9;      // wall time since the last image
  double since_processed_s = 1e9;  // wall time since the last processed frame
  int state = -1;                  // vitamin_e::TrackingStatus state, -1: none yet
  std::string message;             // the last frame's message
  double input_hz = 0.0;           // images received per second (wall clock)
  double processed_hz = 0.0;       // frames processed per second
  bool queue_all = false;          // ~process_all_frames: frames wait in the queue, none is dropped
  std::size_t queued = 0;          // frames waiting in the SLAM thread's queue now
  std::size_t queue_capacity = 1;  // its size (full in bag mode: the image callback waits)
};

struct Health {
  unsigned char level = 0;  // OK 0, WARN 1, ERROR 2
  std::string summary;
};

// ERROR: no calibration; images arriving (or waiting in the SLAM queue) but none processed for
// 2 s; lost.
// WARN: no image yet or for 2 s (and none waiting); initializing; fewer than 80 % of the
// arriving frames processed (live: the rest is dropped by the newest-only queue); the SLAM queue
// full in bag mode (the image callback waits, frames pile up before it, the latency grows).
// OK: tracking at the input rate.
Health trackingHealth(const HealthInput& in);

}  // namespace vitamin_e_ros
