#include "vitamin_e/optimization/ba_window.h"

#include <algorithm>
#include <stdexcept>

namespace vitamin_e {
namespace optimization {

void BaWindowPolicy::validate() const {
  if (num_free_cameras < 0) throw std::invalid_argument("num_free_cameras must be >= 0");
  if (num_fixed_oldest < 0) throw std::invalid_argument("num_fixed_oldest must be >= 0");
  if (min_point_observations < 1) throw std::invalid_argument("min_point_observations must be >= 1");
}

BaWindowSelection selectBaWindow(const BaProblem& problem, const BaWindowPolicy& policy) {
  policy.validate();
  problem.validate();
  const int nc = static_cast<int>(problem.cameras.size());
  const int np = static_cast<int>(problem.points.size());
  BaWindowSelection sel;
  sel.camera_free.assign(nc, false);
  sel.point_free.assign(np, false);
  const int first_free = std::max(policy.num_fixed_oldest, nc - policy.num_free_cameras);
  for (int c = first_free; c < nc; ++c) {
    sel.camera_free[c] = true;
    ++sel.num_free_cameras;
  }
  std::vector<int> count(np, 0);
  std::vector<bool> seen_by_free(np, false);
  for (const BaObservation& o : problem.observations) {
    ++count[o.point];
    if (sel.camera_free[o.camera]) seen_by_free[o.point] = true;
  }
  for (int p = 0; p < np; ++p) {
    const bool free = seen_by_free[p] && count[p] >= policy.min_point_observations &&
                      !(policy.keep_fixed_points && problem.points[p].fixed);
    sel.point_free[p] = free;
    if (free) ++sel.num_free_points;
  }
  for (const BaObservation& o : problem.observations)
    if (sel.camera_free[o.camera] || sel.point_free[o.point]) ++sel.num_active_observations;
  return sel;
}

void applyBaWindow(const BaWindowSelection& selection, BaProblem* problem) {
  if (selection.camera_free.size() != problem->cameras.size() || selection.point_free.size() != problem->points.size())
    throw std::invalid_argument("applyBaWindow: selection does not match the problem");
  for (size_t c = 0; c < problem->cameras.size(); ++c) problem->cameras[c].fixed = !selection.camera_free[c];
  for (size_t p = 0; p < problem->points.size(); ++p) problem->points[p].fixed = !selection.point_free[p];
}

}  // namespace optimization
}  // namespace vitamin_e
