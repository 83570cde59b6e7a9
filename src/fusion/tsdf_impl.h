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
};

}  // namespace vitamin_e::fusion
