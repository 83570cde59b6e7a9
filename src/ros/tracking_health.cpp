#include "vitamin_e/ros/tracking_health.h"

#include <cstdio>

#include <diagnostic_msgs/DiagnosticStatus.h>

#include "vitamin_e/TrackingStatus.h"

namespace vitamin_e_ros {

Health trackingHealth(const HealthInput& in) {
  using DS = diagnostic_msgs::DiagnosticStatus;
  Health h;
  // The worst condition wins; its text is the summary.
  auto raise = [&](unsigned char level, const std::string& text) {
    if (h.summary.empty() || level > h.level) {
      h.level = level;
      h.summary = text;
    }
  };
  if (!in.calibrated) {
    raise(DS::ERROR, "no calibration (~calibration_file or camera_info)");
  } else if (in.received == 0) {
    raise(DS::WARN, "no image received yet");
  } else if (in.since_input_s > 2.0 && in.queued == 0) {
    raise(DS::WARN, "no image for " + std::to_string(static_cast<long>(in.since_input_s)) + " s");
  } else if (in.since_processed_s > 2.0) {
    // In bag mode a full queue holds the callback: no new image is seen, but frames wait.
    raise(DS::ERROR, std::string(in.since_input_s > 2.0 ? "frames wait" : "images arrive") +
                         " but none processed for " + std::to_string(static_cast<long>(in.since_processed_s)) + " s");
  }
  if (in.state == vitamin_e::TrackingStatus::LOST) raise(DS::ERROR, "lost: " + in.message);
  if (in.state == vitamin_e::TrackingStatus::RELOCALIZING) raise(DS::WARN, "relocalizing: " + in.message);
  if (in.state == vitamin_e::TrackingStatus::INITIALIZING) raise(DS::WARN, "initializing");
  if (in.state == vitamin_e::TrackingStatus::TRACKING) raise(DS::OK, "tracking");
  if (in.input_hz > 0.0 && in.since_input_s <= 2.0 && in.processed_hz < 0.8 * in.input_hz) {
    char text[128];
    std::snprintf(text, sizeof(text), "processing %.1f of %.1f frames/s (%s)", in.processed_hz, in.input_hz,
                  in.queue_all ? "queued: the latency grows" : "the rest is dropped");
    raise(DS::WARN, text);
  }
  if (in.queue_all && in.queued >= in.queue_capacity && in.since_processed_s <= 2.0) {
    raise(DS::WARN, "the SLAM queue is full (" + std::to_string(in.queued) +
                        " frames): the input waits, the latency grows (play the bag slower)");
  }
  if (h.summary.empty()) h.summary = "waiting for the first frame";
  return h;
}

}  // namespace vitamin_e_ros
