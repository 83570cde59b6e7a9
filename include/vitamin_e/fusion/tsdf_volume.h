#pragma once
// Voxel-hashed truncated signed distance field. Space is split into blocks of
// block_voxels^3 voxels kept in a hash map keyed by the block index, allocated
// on demand around observed surfaces. integrate() rasterises a frame's mesh
// (z-buffer, inverse depth interpolated linearly in the image, exact for planar
// triangles); each voxel of the blocks near the surface takes the measured depth
// from the raster's pixel nearest to its projection, or, when the raster is
// smaller than the image, from the plane (inverse depth is affine in the image)
// of the triangle seen there, at the projection itself. The voxel is updated
// with the projective signed distance along the ray, truncated, as a running
// weighted average (weight capped at max_weight). extractMesh() runs
// marching cubes (fusion/marching_cubes.h: ambiguous faces resolved from their
// own corner signs, so watertight) on the blocks that changed since the last
// call (and their lower neighbours, which read their voxels), reusing the
// cached triangles of the other blocks; vertices are shared across cubes and
// blocks, so a closed surface gives a closed mesh.
// The voxels stay in the volume's own frame, from which scaling() maps to the
// map's coordinates: the identity until the map is rescaled (setScaling,
// rescale: a ground-scale correction of a monocular map), which moves the whole
// surface at once without touching a voxel. Every argument and result is in map
// coordinates; the voxel size and the truncation are in the volume's units (map
// units when it started, scaled with the map since).
// takeChangedBlocks() hands out the surface of the blocks that changed since
// its last call, for a consumer that keeps a copy (a mesh stream).
#include <Eigen/Geometry>
#include <cstdint>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "vitamin_e/fusion/map_scaling.h"
#include "vitamin_e/fusion/triangle_mesh.h"
#include "vitamin_e/meshing/frame_mesh.h"
#include "vitamin_e/meshing/pinhole_image.h"

namespace vitamin_e::fusion {

struct TsdfConfig {
  // Lengths are in the unit of the poses and depths given: map units in the SLAM
  // (voxel_size and truncation: as the volume started, see TsdfVolume::scaling).
  double voxel_size = 0.05;
  double truncation = 0.15;   // band half-width around the surface
  double max_weight = 100.0;  // cap of the running weight
  int block_voxels = 8;       // voxels per block side
  double min_depth = 0.1;     // rasterised depths outside [min_depth, max_depth] are ignored
  double max_depth = 20.0;
  double min_extract_weight = 0.5;  // voxels lighter than this count as unobserved
  // Measurement weight min(1, (weight_depth_ref / z)^2) (depth noise grows with
  // z^2 for triangulated points); 0: every measurement weighs 1.
  double weight_depth_ref = 0.0;
  // The triangle raster at (width, height) / raster_downscale; 0: from the voxel's size in
  // pixels at the mesh's far depth (half of it, at most 8), so a voxel picks its triangle to
  // within a quarter of its size.
  int raster_downscale = 0;
  void validate() const;  // throws std::invalid_argument naming the key
};

// A TSDF file that cannot be read or does not fit the volume (TsdfVolume::load).
struct TsdfFileError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct Voxel {
  float sdf = 0.0f;     // in [-truncation, truncation]; > 0 in front of the surface
  float weight = 0.0f;  // 0: never observed
};

// The surface inside one voxel block: a triangle soup (three vertices per
// triangle, map coordinates). The triangles of all blocks are those of
// TsdfVolume::extractMesh().
struct MeshBlock {
  Eigen::Vector3i index = Eigen::Vector3i::Zero();  // the block's place in the volume: stable while it lives
  std::vector<Eigen::Vector3f> vertices;
};

// What changed in the surface since the last TsdfVolume::takeChangedBlocks().
struct MeshBlockUpdate {
  // Every block given before is void (the first call, after clear() or load()):
  // `blocks` is the whole surface.
  bool replace_all = false;
  std::vector<MeshBlock> blocks;  // sorted by index; a block without vertices has lost its surface
};

struct IntegrationStats {
  std::size_t blocks_touched = 0;
  std::size_t blocks_allocated = 0;
  std::size_t voxels_updated = 0;
  std::size_t pixels_with_depth = 0;
  int raster_downscale = 1;  // integrate(): the mesh raster's downscale used (TsdfConfig::raster_downscale)
};

class TsdfVolume {
 public:
  explicit TsdfVolume(const TsdfConfig& config = {});
  ~TsdfVolume();
  TsdfVolume(TsdfVolume&&) noexcept;
  TsdfVolume& operator=(TsdfVolume&&) noexcept;

  // Integrates a frame mesh (vertices uv + inv_depth in the camera frame) seen
  // from pose T_w_c.
  IntegrationStats integrate(const meshing::FrameMesh& mesh, const Eigen::Isometry3d& T_w_c,
                             const meshing::PinholeImage& image);
  // Integrates a depth map directly (z along the optical axis, map units; 0 or
  // non-finite: no measurement), CV-free: row-major width*height floats of the
  // image's size.
  IntegrationStats integrateDepth(const std::vector<float>& depth, const Eigen::Isometry3d& T_w_c,
                                  const meshing::PinholeImage& image);
  // Rasterises a mesh into a depth map (row-major, 0 where empty) of the image's size.
  static std::vector<float> rasterizeDepth(const meshing::FrameMesh& mesh, const meshing::PinholeImage& image);

  // Re-runs marching cubes on the blocks changed since the last update
  // (the incremental part); returns the number of blocks re-meshed.
  std::size_t updateMesh();
  // updateMesh(), then assembles the cached per-block triangles into one
  // indexed mesh (vertices shared across blocks, area-weighted normals).
  TriangleMesh extractMesh();
  // Number of blocks re-meshed by the last updateMesh() / extractMesh().
  std::size_t lastRemeshedBlocks() const;
  // updateMesh(), then the blocks whose triangles changed since the last call
  // (all of them after a rescale). A block never reported with a surface is not
  // reported empty.
  MeshBlockUpdate takeChangedBlocks();

  // The map was scaled: map coordinates = volume_to_map.apply(the volume's own).
  void setScaling(const MapScaling& volume_to_map);
  // The map was scaled by `factor` about `centre` (map coordinates), on top of the scaling so far.
  void rescale(const Eigen::Vector3d& centre, double factor);
  const MapScaling& scaling() const;

  // Voxel at a world point (nullptr if its block is not allocated); its sdf is
  // in the volume's units (times scaling().scale: map units).
  const Voxel* voxelAt(const Eigen::Vector3d& p_w) const;
  // Sdf of the voxel containing p_w in map units; false if unobserved.
  bool sdfAt(const Eigen::Vector3d& p_w, double* sdf) const;
  // All voxels (centre in world, value as voxelAt) with weight > 0, for tests and debugging.
  void forEachVoxel(const std::function<void(const Eigen::Vector3d&, const Voxel&)>& fn) const;

  std::size_t numBlocks() const;
  void clear();  // no block, the identity scaling

  // The voxel blocks in a file (src/fusion/tsdf_file.cpp): a readable first
  // line "vitamin_e tsdf v1, N blocks, voxel V, B^3 voxels per block", then the
  // checked binary blocks (common/binary_file.h), written atomically; "v2" when
  // the volume has a scaling, which the file then holds. False (and *error)
  // when it cannot be written.
  bool save(const std::string& path, std::string* error = nullptr) const;
  // Replaces the blocks (and the scaling) with a file's, so that a later run
  // starts with the surface of an earlier one (in the same map's frame and
  // scale). The file's voxel size, block size and truncation must be this
  // volume's. Throws TsdfFileError naming the file and the problem; the volume
  // is then unchanged.
  void load(const std::string& path);
  const TsdfConfig& config() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace vitamin_e::fusion
