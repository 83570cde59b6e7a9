#pragma once
// Map reuse: a new track that appears where an existing map point projects takes
// that point over instead of being triangulated again from the newest (and
// drifted) keyframes. Candidates are the window's landmarks whose track ended
// and the dormant landmarks that left the window; an association needs the same
// curvature sign, no other track nearer to the projection, and no mapped point
// clearly in front of it (the depth of the map points tracked around it).
#include <cstdint>
#include <vector>

#include <Eigen/Geometry>

#include "vitamin_e/camera/camera.h"
#include "vitamin_e/map/map.h"
#include "vitamin_e/pipeline/frame_context.h"
#include "vitamin_e/pipeline/map_update.h"
#include "vitamin_e/pipeline/system_config.h"

namespace vitamin_e::pipeline {

class MapReuse {
 public:
  MapReuse(const SystemConfig& config, const camera::Camera& camera);
  // The map points the frame's unmapped tracks take over, at pose T_w_c
  // (localized): at most one track per point, one point per track.
  // scene_depth: the map's median depth here (a floor on the depths considered).
  // Dormant points are checked in round-robin slices (pipeline.reuse_dormant_per_frame),
  // or all of them with all_dormant (a relocalized frame, whose tracks are all new).
  std::vector<Reassociation> associate(const FrameContext& frame, const Eigen::Isometry3d& T_w_c, double scene_depth,
                                       const map::Map& map, bool all_dormant = false);

 private:
  double radius_px_;
  double occlusion_ratio_;
  std::size_t dormant_per_frame_;
  camera::Camera camera_;
  std::uint64_t dormant_cursor_ = 0;  // next dormant entry to check (in retirement order, see Map::dormantDropped)
};

}  // namespace vitamin_e::pipeline
