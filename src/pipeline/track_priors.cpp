#include "vitamin_e/pipeline/track_priors.h"

namespace vitamin_e::pipeline {

std::vector<tracking::TrackPrior> predictTrackPositions(const TrackPriorSource& source, const camera::Camera& camera,
                                                        double timestamp) {
  std::vector<tracking::TrackPrior> priors;
  if (!source.motion.valid()) return priors;
  const Eigen::Isometry3d T_c_w = source.motion.predict(timestamp).inverse();
  const Eigen::Isometry3d T_last_w = source.motion.lastPose().inverse();
  priors.reserve(source.p_w_by_track.size());
  for (const auto& [id, p_w] : source.p_w_by_track) {
    Eigen::Vector2d uv;
    const Eigen::Vector3d p_c = T_c_w * p_w;
    if (!camera.project(p_c, &uv) || !camera.inImage(uv)) continue;
    const double z_last = (T_last_w * p_w).z();
    const float scale = z_last > 0.0 && p_c.z() > 0.0 ? static_cast<float>(z_last / p_c.z()) : 1.f;
    priors.push_back({id, uv.cast<float>(), scale});
  }
  return priors;
}

}  // namespace vitamin_e::pipeline
