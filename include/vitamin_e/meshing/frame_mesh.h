#pragma once
// Per-frame triangle mesh over the tracked points of one image (pinhole pixels),
// built by FrameMesher and smoothed by NltgvDenoiser; TsdfVolume integrates it.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "vitamin_e/meshing/pinhole_image.h"

namespace vitamin_e::meshing {

struct MeshVertex {
  std::uint64_t id = 0;                          // track id (stable over frames)
  Eigen::Vector2d uv = Eigen::Vector2d::Zero();  // pinhole pixel
  double inv_depth = 0.0;                        // 1 / z in the camera frame (smoothed after denoise())
  double measured_inv_depth = 0.0;               // as given to FrameMesher::build (the data term)
};

struct FrameMesh {
  std::vector<MeshVertex> vertices;
  std::vector<Eigen::Vector3i> triangles;  // indices into vertices

  // Camera-frame position of vertex i (z = 1 / inv_depth).
  Eigen::Vector3d point(std::size_t i, const camera::Pinhole& K) const {
    return K.ray(vertices[i].uv) * (1.0 / vertices[i].inv_depth);
  }
  // Undirected edges (i < j) of the triangles, sorted and unique.
  std::vector<std::pair<int, int>> edges() const;
};

}  // namespace vitamin_e::meshing
