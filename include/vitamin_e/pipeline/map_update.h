#pragma once
// A change of the map a stage computed from the map as it was. Stages read the
// map (const) and return what they would change; System applies it with
// applyMapUpdate, so that the map is written in one place and no stage holds a
// pointer into it across a change.
#include <cstdint>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "vitamin_e/map/map.h"

namespace vitamin_e::pipeline {

// A new track takes over an existing map point (map reuse): an active landmark
// whose track ended (relabelled to the new track's id) or a dormant one (revived).
struct Reassociation {
  std::uint64_t track_id = 0;
  std::int8_t track_polarity = 0;
  std::uint64_t frame_index = 0;  // the frame the track was seen in
  bool dormant = false;
  std::uint64_t landmark_id = 0;  // !dormant: the landmark relabelled
  std::size_t dormant_index = 0;  // dormant: index into map::Map::dormant()
};

struct MapUpdate {
  std::vector<std::pair<std::size_t, Eigen::Isometry3d>> keyframe_poses;  // index into Map::keyframes(), new pose
  std::vector<std::pair<std::uint64_t, Eigen::Vector3d>> positions;       // landmark id, new p_w
  std::vector<Reassociation> reassociations;                              // applied in this order
  // Landmarks that broke a check once more (a pose's outlier, a large BA
  // residual): each counts an offence; at pipeline.max_outlier_count it leaves the map.
  std::vector<std::uint64_t> offenders;
};

struct AppliedMapUpdate {
  std::vector<std::uint64_t> removed;  // landmarks that left the map as offenders: their tracks must end
  int reassociated = 0;                // reassociations the map accepted (see Map::relabelLandmark)
};

// How offenders are treated.
struct OffencePolicy {
  int max_outlier_count = 2;       // pipeline.max_outlier_count
  bool localization_only = false;  // the map must not lose points: an offender is detached (kept dormant)
};

// Applies u in the order keyframe poses, positions, reassociations, offenders.
AppliedMapUpdate applyMapUpdate(const MapUpdate& u, const OffencePolicy& policy, map::Map* map);

}  // namespace vitamin_e::pipeline
