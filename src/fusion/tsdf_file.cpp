// TsdfVolume::save / load: the hashed voxel blocks in a checked binary file.
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "tsdf_impl.h"
#include "vitamin_e/common/binary_file.h"

namespace vitamin_e::fusion {

namespace {
// v1: the blocks; v2: the blocks and the volume's scaling (written only when it is not the identity).
constexpr int kVersion = 1;
constexpr int kScaledVersion = 2;
constexpr std::uint32_t kByteOrderMark = 0x01020304u;
constexpr std::uint32_t kEndMark = 0x46445354u;
const char* const kMagic = "vitamin_e tsdf v";

std::string headerLine(int version, std::size_t blocks, const TsdfConfig& c) {
  char line[160];
  std::snprintf(line, sizeof(line), "vitamin_e tsdf v%d, %zu blocks, voxel %.9g, %d^3 voxels per block", version,
                blocks, c.voxel_size, c.block_voxels);
  return line;
}
}  // namespace

bool TsdfVolume::save(const std::string& path, std::string* error) const {
  const TsdfConfig& c = impl_->config;
  // Blocks sorted by index: the same volume gives the same file.
  std::vector<std::uint64_t> keys;
  keys.reserve(impl_->blocks.size());
  for (const auto& kv : impl_->blocks) keys.push_back(kv.first);
  std::sort(keys.begin(), keys.end());
  BinaryWriter w;
  const std::size_t n3 = static_cast<std::size_t>(c.block_voxels) * c.block_voxels * c.block_voxels;
  w.bytes().reserve(96 + keys.size() * (12 + 8 * n3));
  const MapScaling& scaling = impl_->scaling;
  const int version = scaling.isIdentity() ? kVersion : kScaledVersion;
  w.put(kByteOrderMark);
  w.put(c.voxel_size);
  w.put(c.truncation);
  w.put(static_cast<std::int32_t>(c.block_voxels));
  if (version == kScaledVersion) {
    w.put(scaling.scale);
    w.putDoubles(scaling.offset.data(), 3);
  }
  w.put(static_cast<std::uint64_t>(keys.size()));
  for (std::uint64_t key : keys) {
    const Eigen::Vector3i b = unpackIndex(key);
    for (int k = 0; k < 3; ++k) w.put(static_cast<std::int32_t>(b[k]));
    for (const Voxel& v : impl_->blocks.at(key)->voxels) {
      w.put(v.sdf);
      w.put(v.weight);
    }
  }
  w.put(kEndMark);
  return writeBinaryFile(path, headerLine(version, keys.size(), c), w.bytes(), error);
}

void TsdfVolume::load(const std::string& path) {
  const std::string what = "TSDF file '" + path + "'";
  const TsdfConfig& c = impl_->config;
  std::unordered_map<std::uint64_t, std::unique_ptr<Block>> blocks;
  MapScaling scaling;
  try {
    const BinaryFileContents file = readBinaryFile(path, kMagic, "TSDF", kVersion, kScaledVersion);
    BinaryReader r(file.payload.data(), file.payload.size(), what);
    if (r.get<std::uint32_t>() != kByteOrderMark) r.fail("written with another byte order or damaged");
    const double voxel = r.getFinite("voxel size");
    const double truncation = r.getFinite("truncation");
    const std::int32_t block_voxels = r.get<std::int32_t>();
    // Another grid or band cannot be merged into this volume's voxels.
    if (voxel != c.voxel_size || block_voxels != c.block_voxels || truncation != c.truncation) {
      char buf[256];
      std::snprintf(buf, sizeof(buf),
                    "made with voxel %.9g, %d^3 voxels per block, truncation %.9g; this volume has %.9g, %d^3, %.9g",
                    voxel, block_voxels, truncation, c.voxel_size, c.block_voxels, c.truncation);
      r.fail(buf);
    }
    if (file.version == kScaledVersion) {
      scaling.scale = r.getFinite("scale");
      for (int k = 0; k < 3; ++k) scaling.offset[k] = r.getFinite("offset");
      if (!scaling.isValid()) r.fail("a scale that is not positive");
    }
    const std::size_t n3 = static_cast<std::size_t>(c.block_voxels) * c.block_voxels * c.block_voxels;
    const std::uint64_t count = r.getCount(12 + 8 * n3, "blocks");
    const float max_sdf = static_cast<float>(c.truncation * (1.0 + 1e-6));
    constexpr std::int32_t kLimit = (1 << 20) - 1;  // packIndex range
    blocks.reserve(count);
    for (std::uint64_t i = 0; i < count; ++i) {
      Eigen::Vector3i b;
      for (int k = 0; k < 3; ++k) {
        b[k] = r.get<std::int32_t>();
        if (b[k] < -kLimit || b[k] > kLimit) r.fail("a block index out of range");
      }
      auto block = std::make_unique<Block>();
      block->voxels.resize(n3);
      for (Voxel& v : block->voxels) {
        v.sdf = r.get<float>();
        v.weight = r.get<float>();
        if (!(std::abs(v.sdf) <= max_sdf) || !(v.weight >= 0.0f) || !std::isfinite(v.weight)) {
          r.fail("a voxel outside the truncation band or with a bad weight");
        }
      }
      if (!blocks.emplace(packIndex(b), std::move(block)).second) r.fail("a block appears twice");
    }
    if (r.get<std::uint32_t>() != kEndMark) r.fail("damaged (no end mark after the data)");
    if (r.remaining() != 0) r.fail(std::to_string(r.remaining()) + " bytes after the end mark");
    if (file.header_line != headerLine(file.version, blocks.size(), c)) {
      throw TsdfFileError(what + ": the header line '" + file.header_line + "' does not describe its data");
    }
  } catch (const BinaryFileError& e) {
    throw TsdfFileError(e.what());
  }
  impl_->blocks.swap(blocks);  // every block new: all re-meshed at the next extraction
  impl_->last_remeshed = 0;
  impl_->scaling = scaling;
  impl_->changed.clear();
  impl_->replace_all = true;
}

}  // namespace vitamin_e::fusion
