#include "vitamin_e/pipeline/track_priors.h"

namespace vitamin_e::pipeline {

std::vector<tracking::TrackPrior> predictTrackPositions(const TrackPriorSource& source, const camera::Camera& camera,
                                                        double timestamp) {
  std::vector<tracking::TrackPrior> priors;
  if (!source.motion.valid()) return priors;
  const Eigen::Isometry3d T_c_w = source.motion.predict(timestamp).inverse();
  priors.reserve(source.p_w_by_track.size());
  for (const auto& [id, p_w] : source.p_w_by_track) {
    Eigen::Vector2d uv;
    if (!camera.project(T_c_w * p_w, &uv) || !camera.inImage(uv)) continue;
    priors.push_back({id, uv.cast<float>()});
  }
  return priors;
}

}  // namespace vitamin_e::pipeline
