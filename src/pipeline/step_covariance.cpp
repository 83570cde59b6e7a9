#include "vitamin_e/pipeline/step_covariance.h"

namespace vitamin_e::pipeline {

bool stepCovariance(const FramePose& pose, Eigen::Matrix<double, 6, 6>* covariance, const StepCovarianceModel& model) {
  if (!pose.T_w_c_covariance_valid || !pose.T_w_c_covariance.allFinite()) return false;
  const double k = model.scale * (pose.keyframe ? model.keyframe_scale : 1.0);
  *covariance = k * pose.T_w_c_covariance;
  return true;
}

bool stepCovariance(const FrameResult& result, Eigen::Matrix<double, 6, 6>* covariance,
                    const StepCovarianceModel& model) {
  return result.pose_valid && stepCovariance(poseOf(result), covariance, model);
}

}  // namespace vitamin_e::pipeline
