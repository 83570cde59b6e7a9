#include <cmath>
#include <stdexcept>
#include <string>

#include "vitamin_e/tracking/dense_tracker.h"

namespace vitamin_e::tracking {
namespace {

void require(bool ok, const char* field, const std::string& what) {
  if (!ok) throw std::invalid_argument(std::string("TrackerConfig.") + field + ": " + what);
}

}  // namespace

void TrackerConfig::validate() const {
  require(max_points > 0, "max_points", "must be > 0");
  require(grid_cell_px >= 2, "grid_cell_px", "must be >= 2");
  require(max_per_cell >= 1, "max_per_cell", "must be >= 1");
  require(nms_radius_px >= 1 && nms_radius_px <= 10, "nms_radius_px", "must be in [1, 10]");
  require(border_px >= 2, "border_px", "must be >= 2");
  require(std::isfinite(smoothing_sigma) && smoothing_sigma >= 0.0 && smoothing_sigma <= 10.0, "smoothing_sigma",
          "must be in [0, 10]");
  require(std::isfinite(max_smoothing_sigma) && max_smoothing_sigma >= smoothing_sigma && max_smoothing_sigma <= 10.0,
          "max_smoothing_sigma", "must be in [smoothing_sigma, 10]");
  require(std::isfinite(noise_reference) && noise_reference > 0.0, "noise_reference", "must be > 0");
  require(std::isfinite(kappa_smoothing_sigma) && kappa_smoothing_sigma >= 0.0 && kappa_smoothing_sigma <= 10.0,
          "kappa_smoothing_sigma", "must be in [0, 10]");
  require(std::isfinite(min_curvature) && min_curvature >= 0.0, "min_curvature", "must be finite and >= 0");
  require(std::isfinite(min_abs_curvature) && min_abs_curvature >= 0.0, "min_abs_curvature", "must be finite and >= 0");
  require(std::isfinite(brief_scale) && brief_scale > 0.0 && brief_scale <= 1.0, "brief_scale", "must be in (0, 1]");
  require(brief_max_keypoints >= 3, "brief_max_keypoints", "must be >= 3");
  require(brief_patch_size >= 7 && brief_patch_size % 2 == 1, "brief_patch_size", "must be odd and >= 7");
  require(brief_max_distance >= 0 && brief_max_distance <= 256, "brief_max_distance", "must be in [0, 256]");
  require(std::isfinite(brief_ratio) && brief_ratio > 0.0 && brief_ratio <= 1.0, "brief_ratio", "must be in (0, 1]");
  require(std::isfinite(flow_sigma_px) && flow_sigma_px > 0.0, "flow_sigma_px", "must be > 0");
  require(std::isfinite(flow_sigma_start_px) && flow_sigma_start_px >= flow_sigma_px, "flow_sigma_start_px",
          "must be >= flow_sigma_px");
  require(flow_iterations >= 1, "flow_iterations", "must be >= 1");
  require(flow_min_matches >= 3, "flow_min_matches", "must be >= 3");
  require(std::isfinite(lambda) && lambda >= 0.0, "lambda", "must be finite and >= 0");
  require(std::isfinite(track_sigma_px) && track_sigma_px > 0.0, "track_sigma_px", "must be > 0");
  require(max_climb_steps >= 1, "max_climb_steps", "must be >= 1");
  require(std::isfinite(prediction_blend) && prediction_blend >= 0.0 && prediction_blend < 1.0, "prediction_blend",
          "must be in [0, 1)");
  require(polish_steps >= 0, "polish_steps", "must be >= 0");
  require(std::isfinite(fb_threshold_px) && fb_threshold_px > 0.0, "fb_threshold_px", "must be > 0");
  require(std::isfinite(min_track_curvature) && min_track_curvature >= 0.0, "min_track_curvature",
          "must be finite and >= 0");
  require(std::isfinite(max_curvature_ratio) && max_curvature_ratio >= 1.0, "max_curvature_ratio", "must be >= 1");
  require(std::isfinite(strength_ratio_min_change) && strength_ratio_min_change >= 0.0, "strength_ratio_min_change",
          "must be finite and >= 0");
  require(std::isfinite(min_track_sharpness) && min_track_sharpness >= 0.0, "min_track_sharpness",
          "must be finite and >= 0");
  require(std::isfinite(extremum_weight) && extremum_weight > 0.0 && extremum_weight <= 1.0, "extremum_weight",
          "must be in (0, 1]");
  require(align_radius_px >= 1 && align_radius_px <= 4, "align_radius_px", "must be in [1, 4]");
  require(align_iterations >= 1, "align_iterations", "must be >= 1");
  require(std::isfinite(align_gain_min_change) && align_gain_min_change >= 0.0, "align_gain_min_change",
          "must be finite and >= 0");
  require(std::isfinite(max_align_disagreement_px) && max_align_disagreement_px >= 0.0, "max_align_disagreement_px",
          "must be finite and >= 0");
  require(std::isfinite(confirm_max_unaligned_fraction) && confirm_max_unaligned_fraction >= 0.0 &&
              confirm_max_unaligned_fraction <= 1.0,
          "confirm_max_unaligned_fraction", "must be in [0, 1]");
  require(threads >= 1 && threads <= 64, "threads", "must be in [1, 64]");
}

}  // namespace vitamin_e::tracking
