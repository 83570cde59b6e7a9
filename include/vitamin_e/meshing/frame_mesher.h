#pragma once
// Builds a FrameMesh from a frame's tracked points: 2D Delaunay triangulation of
// the pinhole pixels, then removal of triangles that are too large (longest
// edge in pixels), too oblique (angle between the 3D triangle's normal and the
// viewing ray) or that span a depth discontinuity (relative inverse-depth jump).
#include <cstdint>
#include <vector>

#include "vitamin_e/meshing/frame_mesh.h"

namespace vitamin_e::meshing {

struct FrameMesherConfig {
  double max_edge_px = 60.0;           // drop triangles with a longer edge
  double max_normal_angle_deg = 80.0;  // drop triangles seen more obliquely than this
  double max_inv_depth_jump = 0.25;    // drop if (max - min) / max inverse depth exceeds this
  double min_depth = 0.05;             // points closer (or behind) are ignored
  double max_depth = 50.0;             // points farther are ignored
  bool drop_unused_vertices = true;    // remove vertices that end up in no triangle
  // prune() also applies the jump test to the measured inverse depths (so that
  // smoothing cannot turn a real discontinuity into a kept "curtain").
  bool jump_on_measured = true;
  void validate() const;  // throws std::invalid_argument naming the key
};

class FrameMesher {
 public:
  explicit FrameMesher(const FrameMesherConfig& config = {});
  // ids, uv (pinhole pixels) and depth (z in the camera frame) are parallel arrays.
  // Points outside the image or outside [min_depth, max_depth] are ignored.
  FrameMesh build(const std::vector<std::uint64_t>& ids, const std::vector<Eigen::Vector2d>& uv,
                  const std::vector<double>& depth, const PinholeImage& image) const;
  // Same with camera-frame points p_c (uv = K * p_c, depth = p_c.z()).
  FrameMesh buildFromPoints(const std::vector<std::uint64_t>& ids, const std::vector<Eigen::Vector3d>& p_c,
                            const PinholeImage& image) const;
  // Re-applies the triangle filters to a mesh (e.g. after denoising changed the
  // inverse depths) and drops unused vertices if configured.
  void prune(FrameMesh* mesh, const camera::Pinhole& K) const;
  const FrameMesherConfig& config() const { return config_; }

 private:
  FrameMesherConfig config_;
};

}  // namespace vitamin_e::meshing
