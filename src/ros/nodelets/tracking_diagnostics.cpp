// TrackingNodelet on /diagnostics (diagnostic_updater): input and processed frame rates,
// latency from the image stamp to the published pose (queue wait included), the SLAM queue
// (frames waiting, dropped by the live queue), tracking state, tracked points and
// re-initializations, with OK / WARN / ERROR levels. Reads only the statistics (stats_mutex_)
// and the queue's counts, so a report never waits for a frame being processed.
#include <algorithm>
#include <cmath>
#include <cstdio>


#include "tracking_nodelet.h"
#include "vitamin_e/TrackingStatus.h"
#include "vitamin_e/ros/tracking_health.h"

namespace vitamin_e_ros {

namespace {

constexpr double kWindowS = 5.0;  // rates over the last 5 s (wall clock)

void trim(std::deque<double>* d, double since) {
  while (!d->empty() && d->front() < since) d->pop_front();
}

double rateHz(const std::deque<double>& wall, double now) {
  if (wall.size() < 2) return 0.0;
  // Events per second over the window, measured from the first event in it (a stream that
  // started less than a window ago is not under-counted).
  const double span = std::max(now - wall.front(), 1e-3);
  return static_cast<double>(wall.size() - 1) / std::min(span, kWindowS);
}

}  // namespace

void TrackingNodelet::noteReceived(const ros::Time& stamp) {
  std::lock_guard<std::mutex> lock(stats_mutex_);
  const double now = ros::WallTime::now().toSec();
  stats_.received_wall.push_back(now);
  trim(&stats_.received_wall, now - kWindowS);
  ++stats_.received;
  // The input period from the stamps (median of the last deltas): frames missing between two
  // received stamps were dropped before this nodelet saw them (subscriber queue, network).
  const double t = stamp.toSec();
  const double dt = t - stats_.last_stamp;
  if (stats_.last_stamp > 0.0 && dt > 0.0 && dt < 10.0) {
    if (stats_.period_s > 0.0 && dt > 1.5 * stats_.period_s) {
      stats_.gap_dropped += static_cast<std::size_t>(std::lround(dt / stats_.period_s)) - 1;
    }
    stats_.stamp_deltas.push_back(dt);
    if (stats_.stamp_deltas.size() > 50) stats_.stamp_deltas.pop_front();
    std::vector<double> d(stats_.stamp_deltas.begin(), stats_.stamp_deltas.end());
    std::nth_element(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2), d.end());
    stats_.period_s = d[d.size() / 2];
  }
  stats_.last_stamp = t;
}

void TrackingNodelet::noteRejected() {
  std::lock_guard<std::mutex> lock(stats_mutex_);
  ++stats_.rejected;
}

void TrackingNodelet::diagnose(diagnostic_updater::DiagnosticStatusWrapper& status) {
  SlamQueue<QueuedFrame>::Counts queue;
  if (queue_) queue = queue_->counts();
  std::lock_guard<std::mutex> lock(stats_mutex_);
  const double now = ros::WallTime::now().toSec();
  trim(&stats_.received_wall, now - kWindowS);
  trim(&stats_.processed_wall, now - kWindowS);
  const double input_hz = rateHz(stats_.received_wall, now);
  const double processed_hz = rateHz(stats_.processed_wall, now);
  const double stamp_hz = stats_.period_s > 0.0 ? 1.0 / stats_.period_s : 0.0;
  double latency_mean = 0.0, latency_max = 0.0;
  for (double l : stats_.latency_s) {
    latency_mean += l;
    latency_max = std::max(latency_max, l);
  }
  if (!stats_.latency_s.empty()) latency_mean /= static_cast<double>(stats_.latency_s.size());
  double wait_mean = 0.0;
  for (double w : stats_.queue_wait_s) wait_mean += w;
  if (!stats_.queue_wait_s.empty()) wait_mean /= static_cast<double>(stats_.queue_wait_s.size());
  const double since_input = stats_.received_wall.empty() ? 1e9 : now - stats_.received_wall.back();
  const double since_processed = stats_.processed_wall.empty() ? 1e9 : now - stats_.processed_wall.back();

  HealthInput in;
  in.calibrated = stats_.calibrated;
  in.received = stats_.received;
  in.since_input_s = since_input;
  in.since_processed_s = since_processed;
  in.state = stats_.state;
  in.message = stats_.message;
  in.input_hz = input_hz;
  in.processed_hz = processed_hz;
  in.queue_all = params_.process_all_frames;
  in.queued = queue.waiting;
  in.queue_capacity = queue.capacity;
  const Health health = trackingHealth(in);
  status.summary(health.level, health.summary);
  status.add("state", stats_.state_name.empty() ? "none" : stats_.state_name);
  status.addf("input rate [Hz]", "%.2f", input_hz);
  status.addf("processed rate [Hz]", "%.2f", processed_hz);
  status.addf("camera rate from stamps [Hz]", "%.2f", stamp_hz);
  status.addf("latency image -> pose mean [s]", "%.3f", latency_mean);
  status.addf("latency image -> pose max [s]", "%.3f", latency_max);
  status.add("frames received", stats_.received);
  status.add("frames processed", stats_.processed);
  status.add("frames rejected (bad input)", stats_.rejected);
  status.add("frames queued", queue.waiting);
  status.add("queue capacity", queue.capacity);
  status.add("queue mode",
             params_.process_all_frames ? "every frame (the callback waits when full)" : "newest frame only");
  status.add("SLAM thread busy", queue.busy ? "yes" : "no");
  status.add("frames dropped by the queue", queue.dropped);
  status.addf("queue wait mean [s]", "%.3f", wait_mean);
  status.add("frames missing between stamps", stats_.gap_dropped);
  status.add("tracked points", stats_.tracked);
  status.add("mapped points", stats_.mapped);
  status.add("map size", stats_.map_size);
  status.add("re-initializations", stats_.init_retries);
  status.add("segment", stats_.segment);
  status.add("map", stats_.map);
  status.add("transport", transport_);
  if (!stats_.message.empty()) status.add("message", stats_.message);
}

}  // namespace vitamin_e_ros
