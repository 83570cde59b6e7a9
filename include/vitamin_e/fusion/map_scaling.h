#pragma once
// A scaling of the map without rotation, p -> scale * p + offset: what the
// ground-scale corrections of a monocular map compose to (each one scales the
// whole map by a factor about the camera centre of its keyframe). The TSDF
// keeps its voxels where they were fused and maps them to the map's current
// coordinates with one of these, so a correction costs nothing and loses nothing.
#include <Eigen/Core>
#include <cmath>

namespace vitamin_e::fusion {

struct MapScaling {
  double scale = 1.0;
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();

  // Scaling by `factor` about `centre`: p -> centre + factor * (p - centre).
  static MapScaling about(const Eigen::Vector3d& centre, double factor) { return {factor, (1.0 - factor) * centre}; }
  Eigen::Vector3d apply(const Eigen::Vector3d& p) const { return scale * p + offset; }
  // this after `first`: p -> this(first(p)).
  MapScaling after(const MapScaling& first) const { return {scale * first.scale, scale * first.offset + offset}; }
  MapScaling inverse() const { return {1.0 / scale, -offset / scale}; }
  bool isIdentity() const { return scale == 1.0 && offset.isZero(0.0); }
  // Finite, with a positive scale.
  bool isValid() const { return scale > 0.0 && std::isfinite(scale) && offset.allFinite(); }
  bool operator==(const MapScaling& o) const { return scale == o.scale && offset == o.offset; }
  bool operator!=(const MapScaling& o) const { return !(*this == o); }
};

}  // namespace vitamin_e::fusion
