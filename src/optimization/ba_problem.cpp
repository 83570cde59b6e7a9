#include "vitamin_e/optimization/ba_problem.h"

#include <limits>
#include <stdexcept>
#include <string>

#include "vitamin_e/geometry/projection.h"

namespace vitamin_e {
namespace optimization {

namespace {
constexpr double kMinDepth = 1e-9;
}

void BaProblem::validate() const {
  if (!(K.fx > 0.0) || !(K.fy > 0.0)) throw std::invalid_argument("BaProblem: fx and fy must be > 0");
  const int nc = static_cast<int>(cameras.size());
  const int np = static_cast<int>(points.size());
  for (size_t k = 0; k < observations.size(); ++k) {
    const BaObservation& o = observations[k];
    if (o.camera < 0 || o.camera >= nc || o.point < 0 || o.point >= np)
      throw std::invalid_argument("BaProblem: observation " + std::to_string(k) + " has a bad camera/point index");
  }
}

bool baResidual(const BaProblem& problem, const BaObservation& obs, Eigen::Vector2d* r) {
  const Eigen::Isometry3d& T_w_c = problem.cameras[obs.camera].T_w_c;
  const Eigen::Vector3d p_c = T_w_c.linear().transpose() * (problem.points[obs.point].p_w - T_w_c.translation());
  if (p_c.z() <= kMinDepth) {
    r->setConstant(1e6);
    return false;
  }
  *r = obs.uv - problem.K.projectPoint(p_c);
  return true;
}

double baCost(const BaProblem& problem, double robust_sigma_px) {
  const geometry::GemanMcClure kernel(robust_sigma_px);
  double cost = 0.0;
  Eigen::Vector2d r;
  for (const BaObservation& o : problem.observations) {
    cost += baResidual(problem, o, &r) ? kernel.rho(r.squaredNorm()) : kernel.sigma2;
  }
  return cost;
}

std::vector<double> baResidualNorms(const BaProblem& problem) {
  std::vector<double> out(problem.observations.size());
  Eigen::Vector2d r;
  for (size_t k = 0; k < out.size(); ++k) {
    out[k] = baResidual(problem, problem.observations[k], &r) ? r.norm() : std::numeric_limits<double>::infinity();
  }
  return out;
}

}  // namespace optimization
}  // namespace vitamin_e
