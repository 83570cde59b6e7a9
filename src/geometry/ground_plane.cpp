#include "vitamin_e/geometry/ground_plane.h"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>

namespace vitamin_e {
namespace geometry {

void GroundPlaneConfig::validate() const {
  auto fail = [](const std::string& key, const std::string& what) {
    throw std::invalid_argument("ground." + key + ": " + what);
  };
  if (!(max_tilt_deg > 0.0 && max_tilt_deg < 90.0)) fail("max_tilt_deg", "must be in (0, 90)");
  if (!(min_depression_deg >= 0.0 && min_depression_deg < 90.0)) fail("min_depression_deg", "must be in [0, 90)");
  if (!(inlier_ratio > 0.0 && inlier_ratio < 1.0)) fail("inlier_ratio", "must be in (0, 1)");
  if (min_inliers < 3) fail("min_inliers", "must be >= 3");
  if (!(min_inlier_fraction >= 0.0 && min_inlier_fraction <= 1.0)) fail("min_inlier_fraction", "must be in [0, 1]");
  if (iterations < 1) fail("iterations", "must be >= 1");
}

namespace {

// Plane n.p = d (n unit, d > 0: the camera centre is on the negative side).
struct Plane {
  Eigen::Vector3d n;
  double d;
};

// The plane with unit normal n through `point`, oriented so that the camera centre
// (the origin) is on its negative side; false when the plane passes through it.
bool orientedPlane(Eigen::Vector3d n, const Eigen::Vector3d& point, Plane* p) {
  double d = n.dot(point);
  if (d < 0.0) {
    n = -n;
    d = -d;
  }
  if (!(d > 0.0)) return false;
  p->n = n;
  p->d = d;
  return true;
}

bool planeThrough(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c, Plane* p) {
  const Eigen::Vector3d n = (b - a).cross(c - a);
  const double len = n.norm();
  if (!(len > 1e-12)) return false;
  return orientedPlane(n / len, a, p);
}

// Least-squares plane through the points (smallest eigenvector of their scatter).
bool fitPlane(const std::vector<Eigen::Vector3d>& pts, Plane* p) {
  if (pts.size() < 3) return false;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& q : pts) mean += q;
  mean /= static_cast<double>(pts.size());
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (const auto& q : pts) scatter += (q - mean) * (q - mean).transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(scatter);
  if (eig.info() != Eigen::Success) return false;
  return orientedPlane(eig.eigenvectors().col(0), mean, p);
}

}  // namespace

GroundPlane fitGroundPlane(const std::vector<Eigen::Vector3d>& points_c, const GroundPlaneConfig& config) {
  GroundPlane out;
  const double min_slope = std::tan(config.min_depression_deg * M_PI / 180.0);
  const double cos_tilt = std::cos(config.max_tilt_deg * M_PI / 180.0);
  std::vector<Eigen::Vector3d> cand;
  cand.reserve(points_c.size());
  for (const auto& p : points_c) {
    if (p.allFinite() && p.z() > 0.0 && p.y() > min_slope * p.z()) cand.push_back(p);
  }
  out.candidates = static_cast<int>(cand.size());
  if (out.candidates < config.min_inliers) return out;

  auto count_inliers = [&](const Plane& pl, std::vector<Eigen::Vector3d>* inl) {
    const double tol = config.inlier_ratio * pl.d;
    int n = 0;
    for (const auto& q : cand) {
      if (std::abs(pl.n.dot(q) - pl.d) < tol) {
        ++n;
        if (inl) inl->push_back(q);
      }
    }
    return n;
  };
  std::mt19937 rng(0);  // deterministic runs
  std::uniform_int_distribution<std::size_t> pick(0, cand.size() - 1);
  Plane best{Eigen::Vector3d::UnitY(), 0.0};
  int best_count = 0;
  for (int it = 0; it < config.iterations; ++it) {
    Plane pl;
    if (!planeThrough(cand[pick(rng)], cand[pick(rng)], cand[pick(rng)], &pl)) continue;
    if (pl.n.y() < cos_tilt) continue;  // not the road under a level camera
    const int n = count_inliers(pl, nullptr);
    if (n > best_count) {
      best_count = n;
      best = pl;
    }
  }
  if (best_count < 3) return out;
  // Refine on the inliers, twice (the inlier band moves with the plane).
  for (int pass = 0; pass < 2; ++pass) {
    std::vector<Eigen::Vector3d> inl;
    count_inliers(best, &inl);
    Plane refined;
    if (!fitPlane(inl, &refined) || refined.n.y() < cos_tilt) break;
    best = refined;
  }
  out.inliers = count_inliers(best, nullptr);
  out.height = best.d;
  out.normal_c = best.n;
  out.valid = out.inliers >= config.min_inliers &&
              out.inliers >= config.min_inlier_fraction * static_cast<double>(out.candidates);
  return out;
}

}  // namespace geometry
}  // namespace vitamin_e
