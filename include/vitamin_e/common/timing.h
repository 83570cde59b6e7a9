#pragma once
// Per-stage wall-clock timing: a ScopedTimer adds its duration to a named stage of
// StageTimings; summary() gives mean/median/p95 per stage, for stats.json and the
// timing table printed at the end of a run.
#include <chrono>
#include <map>
#include <string>
#include <vector>

namespace vitamin_e {

struct TimingSummary {
  double mean_ms = 0.0;
  double median_ms = 0.0;
  double p95_ms = 0.0;
  std::size_t count = 0;
};

// Percentile (0..100) of a sample by linear interpolation; 0 for an empty sample.
double percentile(std::vector<double> values, double pct);
// The upper median (element n/2 of the sorted sample, no interpolation); 0 if empty.
double upperMedian(std::vector<double> values);

class StageTimings {
 public:
  void add(const std::string& stage, double ms);
  // Stages in first-seen order.
  const std::vector<std::string>& stages() const { return order_; }
  TimingSummary summary(const std::string& stage) const;
  const std::vector<double>& samples(const std::string& stage) const;
  // A readable table: stage, mean, median, p95, count.
  std::string table() const;
  void clear();

 private:
  std::map<std::string, std::vector<double>> samples_;
  std::vector<std::string> order_;
};

class ScopedTimer {
 public:
  ScopedTimer(StageTimings* timings, std::string stage)
      : timings_(timings), stage_(std::move(stage)), start_(std::chrono::steady_clock::now()) {}
  ~ScopedTimer() { stop(); }
  // Records now; later calls do nothing. Returns the elapsed milliseconds.
  double stop();

 private:
  StageTimings* timings_;
  std::string stage_;
  std::chrono::steady_clock::time_point start_;
  bool stopped_ = false;
  double elapsed_ms_ = 0.0;
};

inline double elapsedMs(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - since).count();
}

}  // namespace vitamin_e
