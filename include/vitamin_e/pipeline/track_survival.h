#pragma once
// How many of the last frame's map tracks a frame keeps, against what this camera
// usually keeps here. What is usual differs by camera and motion (a drone in a
// room keeps about 90 %, a car at speed about 45 %), so a sudden view change (a
// cut, a whip turn) is told by a collapse relative to the recent frames, not by a
// fixed share.
#include <cstddef>
#include <deque>

namespace vitamin_e::pipeline {

class TrackSurvival {
 public:
  // window: the recent tracked frames the usual share is the median of (>= 1).
  explicit TrackSurvival(std::size_t window = 10);
  // A frame's share of the last frame's map tracks still tracked, in [0, 1].
  void add(double fraction);
  // The median of the recent shares; 1 before any.
  double usual() const;
  // fraction is below min_ratio x usual(); never before any share was added.
  bool collapsed(double fraction, double min_ratio) const;
  std::size_t size() const { return recent_.size(); }
  void clear() { recent_.clear(); }

 private:
  std::size_t window_;
  std::deque<double> recent_;
};

}  // namespace vitamin_e::pipeline
