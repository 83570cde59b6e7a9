#pragma once
// Pinhole intrinsics of the undistorted ("pinhole pixel") image used by the
// dense reconstruction: u = fx * x/z + cx, v = fy * y/z + cy.
#include <Eigen/Core>

namespace vitamin_e::meshing {

struct PinholeIntrinsics {
  double fx = 0.0, fy = 0.0, cx = 0.0, cy = 0.0;
  int width = 0, height = 0;

  void validate() const;  // throws std::invalid_argument naming the field

  Eigen::Vector2d project(const Eigen::Vector3d& p_c) const {
    return {fx * p_c.x() / p_c.z() + cx, fy * p_c.y() / p_c.z() + cy};
  }
  // Ray through pinhole pixel uv with z = 1 (normalized coordinates, 1).
  Eigen::Vector3d ray(const Eigen::Vector2d& uv) const {
    return {(uv.x() - cx) / fx, (uv.y() - cy) / fy, 1.0};
  }
  Eigen::Vector3d backProject(const Eigen::Vector2d& uv, double depth) const { return ray(uv) * depth; }
  bool inImage(const Eigen::Vector2d& uv) const {
    return uv.x() >= 0.0 && uv.y() >= 0.0 && uv.x() <= width - 1.0 && uv.y() <= height - 1.0;
  }
};

// From any camera exposing width() height() fx() fy() cx() cy() (e.g.
// camera::Camera: its pinhole pixels are K * normalized undistorted coordinates).
template <typename CameraT>
PinholeIntrinsics pinholeIntrinsicsOf(const CameraT& camera) {
  PinholeIntrinsics K;
  K.fx = camera.fx();
  K.fy = camera.fy();
  K.cx = camera.cx();
  K.cy = camera.cy();
  K.width = camera.width();
  K.height = camera.height();
  return K;
}

}  // namespace vitamin_e::meshing
