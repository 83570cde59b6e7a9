#pragma once
// The one timing facility of the project: elapsedMs() (wall-clock ms since a
// steady_clock time point), processCpuMs() / threadCpuMs() (CPU time, which
// stays meaningful on a loaded machine), ScopedTimer (adds its duration
// to a named stage of StageTimings) and StageTimings (samples per stage,
// mean/median/p95, the timing table printed at the end of a run). A node runs
// for days: a stage keeps at most a bounded number of samples.
#include <chrono>
#include <map>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

namespace vitamin_e {

using TimingClock = std::chrono::steady_clock;

inline double elapsedMs(TimingClock::time_point since) {
  return std::chrono::duration<double, std::milli>(TimingClock::now() - since).count();
}

// CPU time used so far [ms] by all threads of the process, or by the calling thread.
double processCpuMs();
double threadCpuMs();

struct TimingSummary {
  double mean_ms = 0.0;
  double median_ms = 0.0;
  double p95_ms = 0.0;
  std::size_t count = 0;
};

// A frame's gap to the previous one over the interval before that: 2 after one
// dropped frame, 3 after two. A ratio within kSteadyRateTolerance either way is
// a steady rate (stamps jitter) and gives 1, as does an unknown (non-finite or
// non-positive) gap or interval. Motion predicted per frame is scaled by it.
constexpr double kSteadyRateTolerance = 1.25;
double frameGapRatio(double gap_s, double interval_s);

// Percentile (0..100) of a sample by linear interpolation; 0 for an empty sample.
double percentile(std::vector<double> values, double pct);
// The upper median (element n/2 of the sorted sample, no interpolation); 0 if empty.
double upperMedian(std::vector<double> values);

// Thread-safe: stages may be added from several threads (the pipelined system
// tracks and maps on two); readers get copies.
class StageTimings {
 public:
  // 2^16 samples: every frame of the longest dataset sequences; 512 kB per stage.
  static constexpr std::size_t kDefaultMaxSamples = std::size_t{1} << 16;
  // Per stage, the count and the mean are exact; the median and p95 come from at most
  // max_samples_per_stage samples spread evenly over the run (past it every other sample
  // is let go and from then on every 2nd, 4th, ... added one kept).
  explicit StageTimings(std::size_t max_samples_per_stage = kDefaultMaxSamples);
  StageTimings(const StageTimings& other);
  StageTimings& operator=(const StageTimings& other);

  void add(const std::string& stage, double ms);
  // `stage` of `from` added to this one's: its count, mean and kept samples as they are when
  // this one has none of that stage yet, else its kept samples one by one.
  void addStage(const std::string& stage, const StageTimings& from);
  // Stages in first-seen order.
  std::vector<std::string> stages() const;
  TimingSummary summary(const std::string& stage) const;
  std::vector<double> samples(const std::string& stage) const;  // the kept ones, in the order added
  // A readable table: stage, mean, median, p95, count; of every stage in
  // first-seen order, or of the given stages in that order.
  std::string table() const;
  std::string table(const std::vector<std::string>& stages) const;
  void clear();

 private:
  struct Stage {
    std::size_t count = 0;
    double sum_ms = 0.0;
    std::size_t keep_every = 1;  // a sample is kept when its index in the run is a multiple of this
    std::vector<double> kept;
  };
  mutable std::mutex mutex_;
  std::size_t max_samples_;
  std::map<std::string, Stage> stages_;
  std::vector<std::string> order_;
};

// Measures from construction to stop() (or destruction) and adds the duration
// to `stage` of `timings` and, when given, to (*frame_ms)[stage] (a frame's
// own times, e.g. FrameResult::timing_ms).
class ScopedTimer {
 public:
  ScopedTimer(StageTimings* timings, std::string stage, std::map<std::string, double>* frame_ms = nullptr)
      : timings_(timings), frame_ms_(frame_ms), stage_(std::move(stage)), start_(TimingClock::now()) {}
  ~ScopedTimer() { stop(); }
  ScopedTimer(const ScopedTimer&) = delete;
  ScopedTimer& operator=(const ScopedTimer&) = delete;
  // Records now; later calls do nothing. Returns the elapsed milliseconds.
  double stop();

 private:
  StageTimings* timings_;
  std::map<std::string, double>* frame_ms_;
  std::string stage_;
  TimingClock::time_point start_;
  bool stopped_ = false;
  double elapsed_ms_ = 0.0;
};

}  // namespace vitamin_e
