#include "vitamin_e/common/timing.h"

#include <time.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>

namespace vitamin_e {

double processCpuMs() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) * 1e3 + static_cast<double>(ts.tv_nsec) * 1e-6;
}

double threadCpuMs() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) * 1e3 + static_cast<double>(ts.tv_nsec) * 1e-6;
}

double frameGapRatio(double gap_s, double interval_s) {
  if (!std::isfinite(gap_s) || !std::isfinite(interval_s) || !(gap_s > 0.0) || !(interval_s > 0.0)) return 1.0;
  const double r = gap_s / interval_s;
  return r <= kSteadyRateTolerance && r * kSteadyRateTolerance >= 1.0 ? 1.0 : r;
}

double percentile(std::vector<double> values, double pct) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const double pos = std::clamp(pct, 0.0, 100.0) / 100.0 * static_cast<double>(values.size() - 1);
  const std::size_t lo = static_cast<std::size_t>(pos);
  const std::size_t hi = std::min(lo + 1, values.size() - 1);
  const double frac = pos - static_cast<double>(lo);
  return values[lo] * (1.0 - frac) + values[hi] * frac;
}

double upperMedian(std::vector<double> values) {
  if (values.empty()) return 0.0;
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2), values.end());
  return values[values.size() / 2];
}

StageTimings::StageTimings(const StageTimings& other) {
  std::lock_guard<std::mutex> lock(other.mutex_);
  samples_ = other.samples_;
  order_ = other.order_;
}

StageTimings& StageTimings::operator=(const StageTimings& other) {
  if (this == &other) return *this;
  std::scoped_lock lock(mutex_, other.mutex_);
  samples_ = other.samples_;
  order_ = other.order_;
  return *this;
}

void StageTimings::add(const std::string& stage, double ms) {
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = samples_.find(stage);
  if (it == samples_.end()) {
    order_.push_back(stage);
    it = samples_.emplace(stage, std::vector<double>{}).first;
  }
  it->second.push_back(ms);
}

std::vector<std::string> StageTimings::stages() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return order_;
}

std::vector<double> StageTimings::samples(const std::string& stage) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = samples_.find(stage);
  return it == samples_.end() ? std::vector<double>{} : it->second;
}

TimingSummary StageTimings::summary(const std::string& stage) const {
  TimingSummary s;
  const std::vector<double> v = samples(stage);
  if (v.empty()) return s;
  s.count = v.size();
  s.mean_ms = std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(v.size());
  s.median_ms = percentile(v, 50.0);
  s.p95_ms = percentile(v, 95.0);
  return s;
}

std::string StageTimings::table() const { return table(stages()); }

std::string StageTimings::table(const std::vector<std::string>& stages) const {
  std::string out;
  char line[160];
  std::snprintf(line, sizeof(line), "%-24s %10s %10s %10s %8s\n", "stage", "mean ms", "median ms", "p95 ms", "count");
  out += line;
  for (const auto& stage : stages) {
    const TimingSummary s = summary(stage);
    std::snprintf(line, sizeof(line), "%-24s %10.2f %10.2f %10.2f %8zu\n", stage.c_str(), s.mean_ms, s.median_ms,
                  s.p95_ms, s.count);
    out += line;
  }
  return out;
}

void StageTimings::clear() {
  std::lock_guard<std::mutex> lock(mutex_);
  samples_.clear();
  order_.clear();
}

double ScopedTimer::stop() {
  if (stopped_) return elapsed_ms_;
  stopped_ = true;
  elapsed_ms_ = elapsedMs(start_);
  if (timings_) timings_->add(stage_, elapsed_ms_);
  if (frame_ms_) (*frame_ms_)[stage_] = elapsed_ms_;
  return elapsed_ms_;
}

}  // namespace vitamin_e
