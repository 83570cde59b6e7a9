#include "vitamin_e/pipeline/ground_scale.h"

#include <cmath>
#include <stdexcept>

#include "vitamin_e/common/timing.h"

namespace vitamin_e::pipeline {
namespace {

// Every height within max_change of their median.
bool agree(const std::vector<double>& heights, double max_change) {
  const double median = upperMedian(heights);
  for (double h : heights) {
    if (std::abs(median / h - 1.0) > max_change) return false;
  }
  return true;
}

}  // namespace

void GroundScaleConfig::validate() const {
  plane.validate();
  if (reference_keyframes < 1) throw std::invalid_argument("ground.reference_keyframes: must be >= 1");
  if (!(max_step_height_ratio > 0.0)) throw std::invalid_argument("ground.max_step_height_ratio: must be > 0");
  if (window < 1) throw std::invalid_argument("ground.window: must be >= 1");
  if (!(min_inlier_budget_fraction >= 0.0 && min_inlier_budget_fraction <= 1.0))
    throw std::invalid_argument("ground.min_inlier_budget_fraction: must be in [0, 1]");
  if (!(tolerance >= 0.0 && tolerance < 1.0)) throw std::invalid_argument("ground.tolerance: must be in [0, 1)");
  if (!(spread_factor >= 0.0)) throw std::invalid_argument("ground.spread_factor: must be >= 0");
  if (!(gain > 0.0 && gain <= 1.0)) throw std::invalid_argument("ground.gain: must be in (0, 1]");
  if (!(max_change > 0.0 && max_change < 1.0)) throw std::invalid_argument("ground.max_change: must be in (0, 1)");
}

GroundScale::GroundScale(const GroundScaleConfig& config) : config_(config) {}

void GroundScale::reset() {
  first_heights_.clear();
  recent_.clear();
  rejected_.clear();
  reference_ = 0.0;
}

ScaleCorrection GroundScale::update(const std::vector<Eigen::Vector3d>& points_c, double step) {
  ScaleCorrection c;
  if (!config_.enabled) return c;
  const geometry::GroundPlane plane = geometry::fitGroundPlane(points_c, config_.plane);
  c.inliers = plane.inliers;
  c.reference = reference_;
  if (!plane.valid) return c;
  if (step > config_.max_step_height_ratio * plane.height) return c;
  c.measured = true;
  c.height = plane.height;
  if (reference_ <= 0.0) {
    // The first heights that agree among themselves: taken in a turn, while the scale moves
    // fast, they would hold the map to a scale it had for a moment only.
    first_heights_.push_back(plane.height);
    if (static_cast<int>(first_heights_.size()) > config_.reference_keyframes) {
      first_heights_.erase(first_heights_.begin());
    }
    if (static_cast<int>(first_heights_.size()) == config_.reference_keyframes &&
        agree(first_heights_, config_.max_change)) {
      reference_ = upperMedian(first_heights_);
      c.reference = reference_;
    }
    return c;
  }
  // Compared with the map's current height, not the reference: the map may have drifted further.
  const double current = recent_.empty() ? reference_ : upperMedian(recent_);
  if (std::abs(current / plane.height - 1.0) <= config_.max_change) {
    rejected_.clear();
    recent_.push_back(plane.height);
  } else {
    // A kerb or a car roof for a keyframe or two is not the road. A window of consecutive
    // heights that agree among themselves is: the map's scale moved past the gate between
    // two measurements (a turn while the reference was taken), and would never be corrected.
    rejected_.push_back(plane.height);
    if (static_cast<int>(rejected_.size()) < config_.window) return c;
    if (!agree(rejected_, config_.max_change)) {
      rejected_.erase(rejected_.begin());
      return c;
    }
    recent_ = rejected_;
    rejected_.clear();
  }
  if (static_cast<int>(recent_.size()) > config_.window) recent_.erase(recent_.begin());
  if (static_cast<int>(recent_.size()) < config_.window) return c;
  const double median = upperMedian(recent_);
  const double error = reference_ / median - 1.0;
  double allowed = config_.tolerance;
  if (config_.spread_factor > 0.0) {
    std::vector<double> deviations;
    deviations.reserve(recent_.size());
    for (double h : recent_) deviations.push_back(std::abs(h / median - 1.0));
    allowed += config_.spread_factor * upperMedian(deviations);
  }
  if (std::abs(error) <= allowed) return c;
  const double beyond = error > 0.0 ? error - allowed : error + allowed;
  c.factor = 1.0 + config_.gain * beyond;
  for (double& h : recent_) h *= c.factor;  // the map they measured was rescaled
  return c;
}

}  // namespace vitamin_e::pipeline
