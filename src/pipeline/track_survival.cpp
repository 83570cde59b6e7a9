#include "vitamin_e/pipeline/track_survival.h"

#include <algorithm>
#include <stdexcept>
#include <vector>

namespace vitamin_e::pipeline {

TrackSurvival::TrackSurvival(std::size_t window) : window_(window) {
  if (window_ == 0) throw std::invalid_argument("TrackSurvival: window must be >= 1");
}

void TrackSurvival::add(double fraction) {
  recent_.push_back(std::clamp(fraction, 0.0, 1.0));
  if (recent_.size() > window_) recent_.pop_front();
}

double TrackSurvival::usual() const {
  if (recent_.empty()) return 1.0;
  std::vector<double> sorted(recent_.begin(), recent_.end());
  const std::size_t mid = sorted.size() / 2;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(mid), sorted.end());
  if (sorted.size() % 2 == 1) return sorted[mid];
  const double upper = sorted[mid];
  const double lower = *std::max_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(mid));
  return 0.5 * (lower + upper);
}

bool TrackSurvival::collapsed(double fraction, double min_ratio) const {
  return !recent_.empty() && fraction < min_ratio * usual();
}

}  // namespace vitamin_e::pipeline
