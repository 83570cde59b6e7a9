// Incremental marching cubes over the hashed TSDF blocks.
#include <algorithm>
#include <unordered_map>
#include <unordered_set>

#include "tsdf_impl.h"
#include "vitamin_e/fusion/marching_cubes.h"

namespace vitamin_e::fusion {

namespace {
bool sameTriangles(const std::vector<CachedTriangle>& a, const std::vector<CachedTriangle>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (a[i].key != b[i].key) return false;
    for (int k = 0; k < 3; ++k)
      if (a[i].p[k] != b[i].p[k]) return false;
  }
  return true;
}
}  // namespace

void TsdfVolume::Impl::remeshBlock(const Eigen::Vector3i& b, Block* block) const {
  block->triangles.clear();
  const int n = config.block_voxels;
  const float vs = static_cast<float>(config.voxel_size);
  const float min_w = static_cast<float>(config.min_extract_weight);
  const Block* nb[8];
  for (int k = 0; k < 8; ++k) nb[k] = find(b + Eigen::Vector3i(k & 1, (k >> 1) & 1, (k >> 2) & 1));
  auto voxel = [&](int x, int y, int z) -> const Voxel* {
    const int bx = x >= n, by = y >= n, bz = z >= n;
    const Block* blk = nb[bx + 2 * by + 4 * bz];
    if (!blk) return nullptr;
    const int i = (x - bx * n) + n * ((y - by * n) + n * (z - bz * n));
    return &blk->voxels[static_cast<std::size_t>(i)];
  };
  float sdf[8];
  for (int z = 0; z < n; ++z) {
    for (int y = 0; y < n; ++y) {
      for (int x = 0; x < n; ++x) {
        // Cube with lower corner voxel (x, y, z); every corner must be observed.
        int mask = 0;
        bool ok = true;
        for (int k = 0; k < 8 && ok; ++k) {
          const Voxel* v = voxel(x + (k & 1), y + ((k >> 1) & 1), z + ((k >> 2) & 1));
          if (!v || v->weight < min_w) {
            ok = false;
            break;
          }
          sdf[k] = v->sdf;
          if (sdf[k] < 0.0f) mask |= 1 << k;
        }
        if (!ok || mask == 0 || mask == 255) continue;
        const Eigen::Vector3i g0 = b * n + Eigen::Vector3i(x, y, z);  // global index of corner 0
        const std::uint64_t cube_key = packIndex(g0) << 3;
        std::uint64_t key[12 + mc::kMaxCentroids];
        Eigen::Vector3f pos[12 + mc::kMaxCentroids];
        int done = 0;  // bit i: vertex i computed
        auto edge_vertex = [&](int e) {
          if (done & (1 << e)) return;
          // Identity: the edge's lower voxel and its axis (shared across cubes and blocks).
          const int axis = mc::edgeAxis(e), lo = mc::edgeLowerCorner(e), hi = lo | (1 << axis);
          const Eigen::Vector3i g = g0 + Eigen::Vector3i(lo & 1, (lo >> 1) & 1, (lo >> 2) & 1);
          const float s = sdf[lo] / (sdf[lo] - sdf[hi]);
          Eigen::Vector3f p = (g.cast<float>().array() + 0.5f).matrix();
          p[axis] += s;
          key[e] = (packIndex(g) << 3) ^ static_cast<std::uint64_t>(1 << axis);
          pos[e] = p * vs;
          done |= 1 << e;
        };
        for (const std::int8_t* t = mc::caseTriangles(mask); *t >= 0; t += 3) {
          CachedTriangle tri;
          for (int k = 0; k < 3; ++k) {
            const int e = static_cast<std::uint8_t>(t[k]);  // >= 0 in a triangle; -1 only ends the list
            if (e < 12) {
              edge_vertex(e);
            } else if (!(done & (1 << e))) {
              // Centroid of a loop: this cube's own vertex (low bits 0, 3, 5: no edge uses them).
              constexpr std::uint64_t kTag[mc::kMaxCentroids] = {0, 3, 5};
              const std::uint16_t edges = mc::centroidEdges(mask, e - 12);
              Eigen::Vector3f sum = Eigen::Vector3f::Zero();
              int cnt = 0;
              for (int q = 0; q < 12; ++q)
                if (edges & (1u << q)) edge_vertex(q), sum += pos[q], ++cnt;
              pos[e] = sum / static_cast<float>(cnt);
              key[e] = cube_key ^ kTag[e - 12];
              done |= 1 << e;
            }
            tri.key[k] = key[e];
            tri.p[k] = pos[e];
          }
          block->triangles.push_back(tri);
        }
      }
    }
  }
}

std::size_t TsdfVolume::updateMesh() {
  // Re-mesh dirty blocks and the lower neighbours whose cubes read their voxels.
  std::vector<std::uint64_t> todo;
  for (const auto& [key, block] : impl_->blocks) {
    if (!block->dirty) continue;
    const Eigen::Vector3i b = unpackIndex(key);
    for (int k = 0; k < 8; ++k) todo.push_back(packIndex(b - Eigen::Vector3i(k & 1, (k >> 1) & 1, (k >> 2) & 1)));
  }
  std::sort(todo.begin(), todo.end());
  todo.erase(std::unique(todo.begin(), todo.end()), todo.end());
  impl_->last_remeshed = 0;
  std::vector<CachedTriangle> before;
  for (std::uint64_t key : todo) {
    const auto it = impl_->blocks.find(key);
    if (it == impl_->blocks.end()) continue;
    Block* block = it->second.get();
    before.swap(block->triangles);
    impl_->remeshBlock(unpackIndex(key), block);
    // A neighbour re-meshed for a change next door often keeps its surface: not a change.
    if (!sameTriangles(before, block->triangles)) impl_->changed.insert(key);
    ++impl_->last_remeshed;
  }
  for (auto& [key, block] : impl_->blocks) block->dirty = false;
  return impl_->last_remeshed;
}

TriangleMesh TsdfVolume::extractMesh() {
  updateMesh();

  // Assemble: share vertices by edge key, area-weighted vertex normals.
  TriangleMesh mesh;
  std::size_t total = 0;
  for (const auto& kv : impl_->blocks) total += kv.second->triangles.size();
  std::unordered_map<std::uint64_t, int> index;
  index.reserve(total);
  mesh.faces.reserve(total);
  mesh.vertices.reserve(total / 2 + 16);
  for (const auto& kv : impl_->blocks) {
    for (const CachedTriangle& t : kv.second->triangles) {
      Eigen::Vector3i f;
      for (int k = 0; k < 3; ++k) {
        const auto [it, inserted] = index.emplace(t.key[k], static_cast<int>(mesh.vertices.size()));
        if (inserted) mesh.vertices.push_back(impl_->toMap(t.p[k]));
        f[k] = it->second;
      }
      mesh.faces.push_back(f);
    }
  }
  mesh.normals.assign(mesh.vertices.size(), Eigen::Vector3f::Zero());
  for (const auto& f : mesh.faces) {
    const Eigen::Vector3f nrm =
        (mesh.vertices[f[1]] - mesh.vertices[f[0]]).cross(mesh.vertices[f[2]] - mesh.vertices[f[0]]);
    for (int k = 0; k < 3; ++k) mesh.normals[f[k]] += nrm;
  }
  for (auto& nrm : mesh.normals) {
    const float l = nrm.norm();
    nrm = l > 0.0f ? Eigen::Vector3f(nrm / l) : Eigen::Vector3f(0.0f, 0.0f, 1.0f);
  }
  return mesh;
}

MeshBlockUpdate TsdfVolume::takeChangedBlocks() {
  updateMesh();
  MeshBlockUpdate update;
  update.replace_all = impl_->replace_all;
  std::vector<std::uint64_t> keys;
  if (impl_->replace_all) {
    for (const auto& [key, block] : impl_->blocks) {
      block->reported = false;
      if (!block->triangles.empty()) keys.push_back(key);
    }
  } else {
    keys.assign(impl_->changed.begin(), impl_->changed.end());
  }
  std::sort(keys.begin(), keys.end());
  for (std::uint64_t key : keys) {
    const auto it = impl_->blocks.find(key);
    if (it == impl_->blocks.end()) continue;  // only clear() and load() remove blocks: replace_all
    Block& block = *it->second;
    if (block.triangles.empty() && !block.reported) continue;
    MeshBlock out;
    out.index = unpackIndex(key);
    out.vertices.reserve(3 * block.triangles.size());
    for (const CachedTriangle& t : block.triangles)
      for (int k = 0; k < 3; ++k) out.vertices.push_back(impl_->toMap(t.p[k]));
    block.reported = !block.triangles.empty();
    update.blocks.push_back(std::move(out));
  }
  impl_->changed.clear();
  impl_->replace_all = false;
  return update;
}

}  // namespace vitamin_e::fusion
