// Incremental marching tetrahedra over the hashed TSDF blocks.
#include <algorithm>
#include <unordered_map>
#include <unordered_set>

#include "tsdf_impl.h"

namespace vitamin_e::fusion {

namespace {

// Freudenthal split of the unit cube: corner c = x + 2y + 4z; tetrahedron k is the
// monotone path 0 -> e_i -> e_i + e_j -> 7 for the k-th permutation (i, j) of axes.
constexpr int kTets[6][4] = {{0, 1, 3, 7}, {0, 1, 5, 7}, {0, 2, 3, 7}, {0, 2, 6, 7}, {0, 4, 5, 7}, {0, 4, 6, 7}};

struct Corner {
  float sdf;
  Eigen::Vector3f p;  // world position of the voxel centre
  Eigen::Vector3i g;  // global voxel index
  int bits;           // corner index in the cube
};

// Vertex on the tetrahedron edge (a, b): identity from the lower corner and the direction.
struct EdgeVertex {
  std::uint64_t key;
  Eigen::Vector3f p;
};

EdgeVertex edgeVertex(const Corner& a, const Corner& b) {
  const Corner& lo = (a.bits & b.bits) == a.bits ? a : b;  // corner bits of lo are a subset of hi's
  const Corner& hi = (&lo == &a) ? b : a;
  const float t = lo.sdf / (lo.sdf - hi.sdf);
  EdgeVertex v;
  v.key = (packIndex(lo.g) << 3) ^ static_cast<std::uint64_t>(lo.bits ^ hi.bits);
  v.p = lo.p + t * (hi.p - lo.p);
  return v;
}

double orient3d(const Corner& a, const Corner& b, const Corner& c, const Corner& d) {
  return (b.p - a.p).cross(c.p - a.p).dot(d.p - a.p);
}

void emit(std::vector<CachedTriangle>* out, const EdgeVertex& v0, const EdgeVertex& v1, const EdgeVertex& v2) {
  out->push_back({{v0.key, v1.key, v2.key}, {v0.p, v1.p, v2.p}});
}

// Triangles of the zero level set in one tetrahedron, normals pointing to sdf > 0.
void polygonizeTet(const Corner* c[4], std::vector<CachedTriangle>* out) {
  int neg[4], pos[4], nn = 0, np = 0;
  for (int i = 0; i < 4; ++i) (c[i]->sdf < 0.0f ? neg[nn++] : pos[np++]) = i;
  if (nn == 0 || np == 0) return;
  if (nn == 1 || np == 1) {
    // Lone corner a; the triangle cuts its three edges. Facing away from a if a
    // is inside (negative), towards a otherwise.
    const int a = nn == 1 ? neg[0] : pos[0];
    int o[3], k = 0;
    for (int i = 0; i < 4; ++i)
      if (i != a) o[k++] = i;
    const bool away = nn == 1;
    if ((orient3d(*c[a], *c[o[0]], *c[o[1]], *c[o[2]]) > 0.0) != away) std::swap(o[1], o[2]);
    emit(out, edgeVertex(*c[a], *c[o[0]]), edgeVertex(*c[a], *c[o[1]]), edgeVertex(*c[a], *c[o[2]]));
    return;
  }
  // Two inside (a, b), two outside (p, q): quad (a,p) (a,q) (b,q) (b,p).
  int a = neg[0], b = neg[1], p = pos[0], q = pos[1];
  if (orient3d(*c[a], *c[b], *c[p], *c[q]) < 0.0) std::swap(p, q);
  const EdgeVertex v0 = edgeVertex(*c[a], *c[p]), v1 = edgeVertex(*c[a], *c[q]);
  const EdgeVertex v2 = edgeVertex(*c[b], *c[q]), v3 = edgeVertex(*c[b], *c[p]);
  emit(out, v0, v1, v2);
  emit(out, v0, v2, v3);
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
    return &blk->voxels[static_cast<std::size_t>((x - bx * n) + n * ((y - by * n) + n * (z - bz * n)))];
  };
  Corner corners[8];
  for (int z = 0; z < n; ++z) {
    for (int y = 0; y < n; ++y) {
      for (int x = 0; x < n; ++x) {
        bool ok = true, has_neg = false, has_pos = false;
        for (int k = 0; k < 8 && ok; ++k) {
          const int ox = k & 1, oy = (k >> 1) & 1, oz = (k >> 2) & 1;
          const Voxel* v = voxel(x + ox, y + oy, z + oz);
          if (!v || v->weight < min_w) {
            ok = false;
            break;
          }
          Corner& c = corners[k];
          c.sdf = v->sdf;
          c.bits = k;
          c.g = b * n + Eigen::Vector3i(x + ox, y + oy, z + oz);
          (c.sdf < 0.0f ? has_neg : has_pos) = true;
        }
        if (!ok || !has_neg || !has_pos) continue;
        for (auto& c : corners) c.p = (c.g.cast<float>().array() + 0.5f).matrix() * vs;
        for (const auto& tet : kTets) {
          const Corner* tc[4] = {&corners[tet[0]], &corners[tet[1]], &corners[tet[2]], &corners[tet[3]]};
          polygonizeTet(tc, &block->triangles);
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
  for (std::uint64_t key : todo) {
    const auto it = impl_->blocks.find(key);
    if (it == impl_->blocks.end()) continue;
    impl_->remeshBlock(unpackIndex(key), it->second.get());
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
        if (inserted) mesh.vertices.push_back(t.p[k]);
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

}  // namespace vitamin_e::fusion
