#include "vitamin_e/pipeline/dense_input.h"

#include <cmath>

#include "vitamin_e/pipeline/system.h"

namespace vitamin_e::pipeline {

fusion::DenseFrame DenseInput::next(const FrameResult& result, bool with_points) {
  const double factor = result.diagnostics.scale_correction;
  if (factor != 1.0 && factor > 0.0 && std::isfinite(factor) && result.T_w_c.translation().allFinite()) {
    map_scaling_ = fusion::MapScaling::about(result.T_w_c.translation(), factor).after(map_scaling_);
  }
  fusion::DenseFrame frame;
  frame.frame_index = result.frame_index;
  frame.T_w_c = result.T_w_c;
  frame.map_scaling = map_scaling_;
  if (with_points) framePointsInCamera(result, &frame.ids, &frame.p_c);
  return frame;
}

}  // namespace vitamin_e::pipeline
