#include "vitamin_e/pipeline/map_update.h"

namespace vitamin_e::pipeline {

AppliedMapUpdate applyMapUpdate(const MapUpdate& u, const OffencePolicy& policy, map::Map* map) {
  AppliedMapUpdate out;
  for (const auto& [index, T_w_c] : u.keyframe_poses) map->setKeyframePose(index, T_w_c);
  for (const auto& [id, p_w] : u.positions) map->setLandmarkPosition(id, p_w);
  for (const Reassociation& r : u.reassociations) {
    const bool ok = r.dormant ? map->reviveDormant(r.dormant_index, r.track_id, r.frame_index, r.track_polarity)
                              : map->relabelLandmark(r.landmark_id, r.track_id, r.frame_index, r.track_polarity);
    if (ok) ++out.reassociated;
  }
  // Every offence is counted before any offender leaves the map.
  for (std::uint64_t id : u.offenders) {
    if (map->flagOutlier(id) >= policy.max_outlier_count) out.removed.push_back(id);
  }
  for (std::uint64_t id : out.removed) {
    if (policy.localization_only) {
      map->detachLandmark(id);
    } else {
      map->removeLandmark(id);
    }
  }
  return out;
}

}  // namespace vitamin_e::pipeline
