#pragma once
// The undistorted ("pinhole pixel") image the dense reconstruction works in: its
// intrinsics K (camera::Pinhole, u = fx * x/z + cx, v = fy * y/z + cy) and its size.
#include <Eigen/Core>

#include "vitamin_e/camera/camera.h"

namespace vitamin_e::meshing {

struct PinholeImage {
  camera::Pinhole K;
  int width = 0, height = 0;

  void validate() const;  // throws std::invalid_argument naming the field

  bool inImage(const Eigen::Vector2d& uv) const {
    return uv.x() >= 0.0 && uv.y() >= 0.0 && uv.x() <= width - 1.0 && uv.y() <= height - 1.0;
  }
  bool operator==(const PinholeImage& o) const { return K == o.K && width == o.width && height == o.height; }
  bool operator!=(const PinholeImage& o) const { return !(*this == o); }
};

// The camera's pinhole part and size: its pinhole pixels are K * normalized undistorted coordinates.
inline PinholeImage pinholeImageOf(const camera::Camera& camera) {
  return {camera.pinhole(), camera.width(), camera.height()};
}

}  // namespace vitamin_e::meshing
