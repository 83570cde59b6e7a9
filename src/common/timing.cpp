#include "vitamin_e/common/timing.h"

#include <algorithm>
#include <cstdio>
#include <numeric>

namespace vitamin_e {

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
  std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
  return values[values.size() / 2];
}

void StageTimings::add(const std::string& stage, double ms) {
  auto it = samples_.find(stage);
  if (it == samples_.end()) {
    order_.push_back(stage);
    it = samples_.emplace(stage, std::vector<double>{}).first;
  }
  it->second.push_back(ms);
}

const std::vector<double>& StageTimings::samples(const std::string& stage) const {
  static const std::vector<double> kEmpty;
  auto it = samples_.find(stage);
  return it == samples_.end() ? kEmpty : it->second;
}

TimingSummary StageTimings::summary(const std::string& stage) const {
  TimingSummary s;
  const auto& v = samples(stage);
  if (v.empty()) return s;
  s.count = v.size();
  s.mean_ms = std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(v.size());
  s.median_ms = percentile(v, 50.0);
  s.p95_ms = percentile(v, 95.0);
  return s;
}

std::string StageTimings::table() const {
  std::string out;
  char line[160];
  std::snprintf(line, sizeof(line), "%-24s %10s %10s %10s %8s\n", "stage", "mean ms", "median ms", "p95 ms", "count");
  out += line;
  for (const auto& stage : order_) {
    const TimingSummary s = summary(stage);
    std::snprintf(line, sizeof(line), "%-24s %10.2f %10.2f %10.2f %8zu\n", stage.c_str(), s.mean_ms, s.median_ms,
                  s.p95_ms, s.count);
    out += line;
  }
  return out;
}

void StageTimings::clear() {
  samples_.clear();
  order_.clear();
}

double ScopedTimer::stop() {
  if (stopped_) return elapsed_ms_;
  stopped_ = true;
  elapsed_ms_ = elapsedMs(start_);
  if (timings_) timings_->add(stage_, elapsed_ms_);
  return elapsed_ms_;
}

}  // namespace vitamin_e
