#include "vitamin_e/common/timing.h"

#include <time.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

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

StageTimings::StageTimings(std::size_t max_samples_per_stage)
    : max_samples_(std::max<std::size_t>(max_samples_per_stage, 2)) {}

StageTimings::StageTimings(const StageTimings& other) {
  std::lock_guard<std::mutex> lock(other.mutex_);
  max_samples_ = other.max_samples_;
  stages_ = other.stages_;
  order_ = other.order_;
}

StageTimings& StageTimings::operator=(const StageTimings& other) {
  if (this == &other) return *this;
  std::scoped_lock lock(mutex_, other.mutex_);
  max_samples_ = other.max_samples_;
  stages_ = other.stages_;
  order_ = other.order_;
  return *this;
}

void StageTimings::add(const std::string& stage, double ms) {
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = stages_.find(stage);
  if (it == stages_.end()) {
    order_.push_back(stage);
    it = stages_.emplace(stage, Stage{}).first;
  }
  Stage& s = it->second;
  ++s.count;
  s.sum_ms += ms;
  if ((s.count - 1) % s.keep_every != 0) return;
  if (s.kept.size() == max_samples_) {  // full: keep every other one, and from now on half as many
    std::size_t n = 0;
    for (std::size_t i = 0; i < s.kept.size(); i += 2) s.kept[n++] = s.kept[i];
    s.kept.resize(n);
    s.keep_every *= 2;
    if ((s.count - 1) % s.keep_every != 0) return;
  }
  s.kept.push_back(ms);
}

void StageTimings::addStage(const std::string& stage, const StageTimings& from) {
  if (&from == this) return;
  Stage theirs;
  {
    std::lock_guard<std::mutex> lock(from.mutex_);
    const auto it = from.stages_.find(stage);
    if (it == from.stages_.end() || it->second.count == 0) return;
    theirs = it->second;
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto it = stages_.find(stage);
    if ((it == stages_.end() || it->second.count == 0) && theirs.kept.size() <= max_samples_) {
      if (it == stages_.end()) order_.push_back(stage);
      stages_[stage] = std::move(theirs);
      return;
    }
  }
  for (double ms : theirs.kept) add(stage, ms);
}

std::vector<std::string> StageTimings::stages() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return order_;
}

std::vector<double> StageTimings::samples(const std::string& stage) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = stages_.find(stage);
  return it == stages_.end() ? std::vector<double>{} : it->second.kept;
}

TimingSummary StageTimings::summary(const std::string& stage) const {
  TimingSummary s;
  std::vector<double> v;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = stages_.find(stage);
    if (it == stages_.end() || it->second.count == 0) return s;
    s.count = it->second.count;
    s.mean_ms = it->second.sum_ms / static_cast<double>(it->second.count);
    v = it->second.kept;
  }
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
  stages_.clear();
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
