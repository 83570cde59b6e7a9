#pragma once
// Private state of TsdfVolume, shared by tsdf_volume.cpp (integration) and
// tsdf_extract.cpp (marching cubes).
#include <array>
#include <cstdint>
#include <memory>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "vitamin_e/fusion/tsdf_volume.h"

namespace vitamin_e::fusion {

// Global voxel / block coordinates packed into 64 bits (21 bits per axis, offset).
inline std::uint64_t packIndex(const Eigen::Vector3i& b) {
  constexpr std::int64_t kOff = 1 << 20;
  return (static_cast<std::uint64_t>(b.x() + kOff) << 42) | (static_cast<std::uint64_t>(b.y() + kOff) << 21) |
         static_cast<std::uint64_t>(b.z() + kOff);
}
inline Eigen::Vector3i unpackIndex(std::uint64_t k) {
  constexpr std::int64_t kOff = 1 << 20;
  constexpr std::uint64_t kMask = (1ULL << 21) - 1;
  return {static_cast<int>(static_cast<std::int64_t>((k >> 42) & kMask) - kOff),
          static_cast<int>(static_cast<std::int64_t>((k >> 21) & kMask) - kOff),
          static_cast<int>(static_cast<std::int64_t>(k & kMask) - kOff)};
}

struct CachedTriangle {
  std::array<std::uint64_t, 3> key;  // vertex identity: (lower voxel, edge direction)
  std::array<Eigen::Vector3f, 3> p;
};

struct Block {
  std::vector<Voxel> voxels;  // x fastest: x + n * (y + n * z)
  bool dirty = true;
  std::vector<CachedTriangle> triangles;  // volume coordinates
  bool reported = false;                  // takeChangedBlocks() gave it with triangles last time
};

// A frame mesh rasterised for fusion (TsdfVolume::integrate): the triangle seen at each pixel of
// a raster of (width, height) = the image's / s, and every triangle's plane in the full image.
struct MeshRaster {
  // Inverse depth inv0 + du (u - u0) + dv (v - v0) at the full image's pixel (u, v).
  struct Plane {
    double u0 = 0.0, v0 = 0.0, inv0 = 0.0, du = 0.0, dv = 0.0;
  };
  int s = 1, width = 0, height = 0;
  std::vector<int> triangle;  // per raster pixel, row-major; -1: none
  std::vector<Plane> planes;  // per mesh triangle
};

struct TsdfVolume::Impl {
  TsdfConfig config;
  std::unordered_map<std::uint64_t, std::unique_ptr<Block>> blocks;
  std::size_t last_remeshed = 0;
  MapScaling scaling;                         // volume -> map coordinates
  std::unordered_set<std::uint64_t> changed;  // blocks whose triangles changed since takeChangedBlocks()
  bool replace_all = true;                    // ... or all of them: the next update replaces everything

  double blockSize() const { return config.voxel_size * config.block_voxels; }
  // A vertex in map coordinates (exactly the cached one while the scaling is the identity).
  Eigen::Vector3f toMap(const Eigen::Vector3f& p_v) const {
    if (scaling.isIdentity()) return p_v;
    return scaling.apply(p_v.cast<double>()).cast<float>();
  }
  Block* find(const Eigen::Vector3i& b) const {
    const auto it = blocks.find(packIndex(b));
    return it == blocks.end() ? nullptr : it->second.get();
  }
  void remeshBlock(const Eigen::Vector3i& b, Block* block) const;  // tsdf_extract.cpp
  // Updates the voxels near the measured surface (tsdf_volume.cpp): `depth` (map units, on
  // depth_image's pixels) finds the blocks; the voxels read it at their nearest pixel, or, with
  // `mesh`, the mesh's planes at their projection into `image`.
  IntegrationStats fuse(const std::vector<float>& depth, const meshing::PinholeImage& depth_image,
                        const MeshRaster* mesh, const meshing::PinholeImage& image, const Eigen::Isometry3d& T_map_c);
  std::vector<std::uint64_t> keys;  // fuse()'s blocks, kept for their buffer
};

}  // namespace vitamin_e::fusion
