#pragma once
// Pinhole intrinsics K = (fx, fy, cx, cy): the one owner of "pinhole pixel = K * normalized".
// camera::Camera adds the image size and the lens distortion; the geometry, the bundle
// adjustment and the dense reconstruction work in pinhole pixels with this type alone.
//
// Coordinates (docs/DEVELOPING.md): "normalized" are undistorted (x/z, y/z) in the optical
// camera frame (z forward); "pinhole pixels" are K * [x y 1].
#include <Eigen/Core>
#include <Eigen/Geometry>  // homogeneous()

namespace vitamin_e::camera {

struct Pinhole {
  double fx = 1.0, fy = 1.0, cx = 0.0, cy = 0.0;

  // Normalized -> pinhole pixel.
  Eigen::Vector2d project(const Eigen::Vector2d& xy) const { return {fx * xy.x() + cx, fy * xy.y() + cy}; }
  // Pinhole pixel -> normalized.
  Eigen::Vector2d unproject(const Eigen::Vector2d& uv) const { return {(uv.x() - cx) / fx, (uv.y() - cy) / fy}; }
  // Pinhole pixel -> the ray through it with z = 1: (normalized, 1).
  Eigen::Vector3d ray(const Eigen::Vector2d& uv) const { return unproject(uv).homogeneous(); }
  // Camera-frame point -> pinhole pixel (z > 0 is the caller's check).
  Eigen::Vector2d projectPoint(const Eigen::Vector3d& p_c) const {
    const double iz = 1.0 / p_c.z();
    return {fx * p_c.x() * iz + cx, fy * p_c.y() * iz + cy};
  }
  // d projectPoint / d p_c.
  Eigen::Matrix<double, 2, 3> projectPointJacobian(const Eigen::Vector3d& p_c) const {
    const double iz = 1.0 / p_c.z();
    const double iz2 = iz * iz;
    Eigen::Matrix<double, 2, 3> J;
    J << fx * iz, 0.0, -fx * p_c.x() * iz2, 0.0, fy * iz, -fy * p_c.y() * iz2;
    return J;
  }
  // K of the image binned by (bx, by): a binned pixel u covers pixels [bx u, bx u + bx), so
  // its centre is at bx u + (bx - 1) / 2 (pixel centres at integer coordinates).
  Pinhole binned(double bx, double by) const {
    return {fx / bx, fy / by, (cx + 0.5) / bx - 0.5, (cy + 0.5) / by - 0.5};
  }
  Eigen::Matrix3d matrix() const {
    Eigen::Matrix3d k;
    k << fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0;
    return k;
  }
  // fx, fy finite and > 0; cx, cy finite.
  bool valid() const;
  bool operator==(const Pinhole& o) const { return fx == o.fx && fy == o.fy && cx == o.cx && cy == o.cy; }
  bool operator!=(const Pinhole& o) const { return !(*this == o); }
};

}  // namespace vitamin_e::camera
