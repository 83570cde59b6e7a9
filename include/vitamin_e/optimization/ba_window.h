#pragma once
// Window management for per-frame bundle adjustment: decides which cameras and points of a
// BaProblem are free so that the cost per frame stays bounded.
//
// Policy (cameras are ordered by time = their index in problem.cameras):
//  - the newest `num_free_cameras` cameras are free, except that the oldest `num_fixed_oldest`
//    cameras are always fixed (monocular gauge: pose and scale; two fixed cameras fix the
//    7-DoF similarity gauge);
//  - all other cameras are fixed (they were optimized when they were new);
//  - a point is free iff it is observed by at least one free camera and has at least
//    `min_point_observations` observations in the problem (a point seen once is unconstrained
//    along its ray) and it is not marked `fixed` by the caller (keep_fixed_points);
//  - everything else is fixed: observations with nothing free are constant and skipped.
// The cost of one solve is then O(observations of the free cameras + observations of their
// points), independent of how many old cameras/points the window holds.
#include <vector>

#include "vitamin_e/optimization/ba_problem.h"

namespace vitamin_e {
namespace optimization {

struct BaWindowPolicy {
  int num_free_cameras = 3;        // newest cameras optimized each frame
  int num_fixed_oldest = 2;        // gauge: always fixed
  int min_point_observations = 2;  // points with fewer observations stay fixed
  bool keep_fixed_points = true;   // points already marked fixed stay fixed
  void validate() const;           // throws std::invalid_argument naming the key
};

struct BaWindowSelection {
  std::vector<bool> camera_free;  // per problem camera
  std::vector<bool> point_free;   // per problem point
  int num_free_cameras = 0;
  int num_free_points = 0;
  int num_active_observations = 0;  // observations touching a free variable
};

BaWindowSelection selectBaWindow(const BaProblem& problem, const BaWindowPolicy& policy);

// Writes the selection into the fixed flags of the problem.
void applyBaWindow(const BaWindowSelection& selection, BaProblem* problem);

}  // namespace optimization
}  // namespace vitamin_e
