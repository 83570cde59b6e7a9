#pragma once
// Depth maps of spheres seen from cameras around them, for the TSDF tests.
#include <cmath>
#include <vector>

#include <Eigen/Geometry>

#include "vitamin_e/meshing/pinhole_image.h"

namespace vitamin_e::test {

inline meshing::PinholeImage sphereTestImage() { return {{200.0, 200.0, 159.5, 119.5}, 320, 240}; }

// Camera at `eye` looking at `target` (optical frame: z forward, y down-ish).
inline Eigen::Isometry3d lookAt(const Eigen::Vector3d& eye, const Eigen::Vector3d& target) {
  const Eigen::Vector3d z = (target - eye).normalized();
  const Eigen::Vector3d up = std::abs(z.z()) > 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d x = z.cross(up).normalized();
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear().col(0) = x;
  T.linear().col(1) = z.cross(x);
  T.linear().col(2) = z;
  T.translation() = eye;
  return T;
}

// Depth map (z) of a sphere (centre c, radius r, world) seen from T_w_c.
inline std::vector<float> sphereDepth(const Eigen::Vector3d& c, double r, const Eigen::Isometry3d& T_w_c,
                                      const meshing::PinholeImage& image) {
  std::vector<float> depth(static_cast<std::size_t>(image.width) * image.height, 0.0f);
  const Eigen::Vector3d c_c = T_w_c.inverse() * c;
  for (int v = 0; v < image.height; ++v) {
    for (int u = 0; u < image.width; ++u) {
      const Eigen::Vector3d ray = image.K.ray(Eigen::Vector2d(u, v));  // z = 1
      const double a = ray.squaredNorm(), b = -2.0 * ray.dot(c_c), cc = c_c.squaredNorm() - r * r;
      const double disc = b * b - 4 * a * cc;
      if (disc < 0) continue;
      const double t = (-b - std::sqrt(disc)) / (2 * a);
      if (t > 0) depth[static_cast<std::size_t>(v) * image.width + u] = static_cast<float>(t);
    }
  }
  return depth;
}

// Cameras at `dist` from c in the 26 directions of a cube's faces, edges and corners.
inline std::vector<Eigen::Isometry3d> viewsAround(const Eigen::Vector3d& c, double dist) {
  std::vector<Eigen::Isometry3d> views;
  for (int sx = -1; sx <= 1; ++sx)
    for (int sy = -1; sy <= 1; ++sy)
      for (int sz = -1; sz <= 1; ++sz) {
        if (sx == 0 && sy == 0 && sz == 0) continue;
        views.push_back(lookAt(c + dist * Eigen::Vector3d(sx, sy, sz).normalized(), c));
      }
  return views;
}

}  // namespace vitamin_e::test
