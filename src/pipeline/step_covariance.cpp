#include "vitamin_e/pipeline/step_covariance.h"

namespace vitamin_e::pipeline {

bool stepCovariance(const FrameResult& result, Eigen::Matrix<double, 6, 6>* covariance,
                    const StepCovarianceModel& model) {
  if (!result.pose_valid || !result.T_w_c_covariance_valid || !result.T_w_c_covariance.allFinite()) return false;
  const double k = model.scale * (result.diagnostics.keyframe ? model.keyframe_scale : 1.0);
  *covariance = k * result.T_w_c_covariance;
  return true;
}

}  // namespace vitamin_e::pipeline
