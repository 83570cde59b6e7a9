// Marching cubes: the case table derived from the face rule (see marching_cubes.h).
#include "vitamin_e/fusion/marching_cubes.h"

#include <Eigen/Geometry>
#include <array>
#include <cstdlib>
#include <stdexcept>
#include <unordered_map>

namespace vitamin_e::fusion::mc {

namespace {

constexpr int kMaxEntries = 3 * 12 + 1;  // at most 12 triangles + terminator

// Lower corners of the edges along x, y, z (the corners with that axis' bit clear).
constexpr int kEdgeLo[12] = {0, 2, 4, 6, 0, 1, 4, 5, 0, 1, 2, 3};

Eigen::Vector3d cornerPos(int c) { return Eigen::Vector3d(c & 1, (c >> 1) & 1, (c >> 2) & 1); }

int edgeBetween(int p, int q) {
  const int axis = (p ^ q) == 1 ? 0 : (p ^ q) == 2 ? 1 : 2;
  const int lo = p & q;
  for (int k = 0; k < 4; ++k)
    if (kEdgeLo[axis * 4 + k] == lo) return axis * 4 + k;
  std::abort();  // p, q are not the ends of a cube edge
}

Eigen::Vector3d edgeMid(int e) { return cornerPos(kEdgeLo[e]) + 0.5 * Eigen::Vector3d::Unit(e / 4); }

// True if cube edges a and b lie on a common face (then the neighbour across
// that face also holds both, and a triangle edge between them must be a segment).
bool shareFace(int a, int b) {
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      auto on = [&](int e) { return e / 4 != axis && ((kEdgeLo[e] >> axis) & 1) == side; };
      if (on(a) && on(b)) return true;
    }
  return false;
}

struct Table {
  std::array<std::array<std::int8_t, kMaxEntries>, 256> tris;
  std::array<std::array<std::uint16_t, kMaxCentroids>, 256> centroids{};
  Table() {
    for (int mask = 0; mask < 256; ++mask) build(mask);
  }

  void build(int mask) {
    auto inside = [mask](int c) { return ((mask >> c) & 1) != 0; };
    // next[e]: the segment leaving the crossing on edge e (-1: none).
    std::array<int, 12> next;
    next.fill(-1);
    auto add_segment = [&](int ea, int eb, const Eigen::Vector3d& n, int ref_corner, bool ref_outside) {
      const Eigen::Vector3d a = edgeMid(ea), b = edgeMid(eb);
      const Eigen::Vector3d left = n.cross(b - a);
      const bool ref_left = left.dot(cornerPos(ref_corner) - a) > 0.0;
      if (ref_left != ref_outside) std::swap(ea, eb);  // outside on the left, seen from outside
      if (next[ea] != -1) throw std::logic_error("marching cubes table: two segments leave one edge");
      next[ea] = eb;
    };
    for (int axis = 0; axis < 3; ++axis)
      for (int side = 0; side < 2; ++side) {
        const int b = (axis + 1) % 3, c = (axis + 2) % 3;
        // The face's corners in cyclic order.
        const int ring[4] = {side << axis, (side << axis) | (1 << b), (side << axis) | (1 << b) | (1 << c),
                             (side << axis) | (1 << c)};
        const Eigen::Vector3d n = (side ? 1.0 : -1.0) * Eigen::Vector3d::Unit(axis);
        int crossings[4], nc = 0;
        for (int k = 0; k < 4; ++k)
          if (inside(ring[k]) != inside(ring[(k + 1) % 4])) crossings[nc++] = edgeBetween(ring[k], ring[(k + 1) % 4]);
        if (nc == 2) {
          int ref = ring[0];
          for (int k = 0; k < 4; ++k)
            if (!inside(ring[k])) ref = ring[k];
          add_segment(crossings[0], crossings[1], n, ref, true);
        } else if (nc == 4) {  // diagonal pattern: cut off each inside corner
          for (int k = 0; k < 4; ++k) {
            if (!inside(ring[k])) continue;
            const int e0 = edgeBetween(ring[(k + 3) % 4], ring[k]), e1 = edgeBetween(ring[k], ring[(k + 1) % 4]);
            add_segment(e0, e1, n, ring[k], false);
          }
        }
      }
    // Chain the segments into loops and fan each loop.
    auto& out = tris[mask];
    int w = 0, nc_used = 0;
    std::array<bool, 12> used{};
    for (int start = 0; start < 12; ++start) {
      if (next[start] == -1 || used[start]) continue;
      int loop[12], len = 0;
      for (int e = start; !used[e]; e = next[e]) {
        if (next[e] == -1) throw std::logic_error("marching cubes table: open loop");
        used[e] = true;
        loop[len++] = e;
      }
      // Fan from a vertex none of whose diagonals joins two edges of one face
      // (such a diagonal could also be made by the neighbouring cube: a
      // non-manifold edge); if there is none, fan around the loop's centroid.
      int apex = -1;
      for (int s = 0; s < len && apex < 0; ++s) {
        bool ok = true;
        for (int k = 2; k + 1 < len && ok; ++k) ok = !shareFace(loop[s], loop[(s + k) % len]);
        if (ok) apex = s;
      }
      if (apex >= 0) {
        for (int k = 1; k + 1 < len; ++k) {
          out[w++] = static_cast<std::int8_t>(loop[apex]);
          out[w++] = static_cast<std::int8_t>(loop[(apex + k) % len]);
          out[w++] = static_cast<std::int8_t>(loop[(apex + k + 1) % len]);
        }
      } else {
        if (nc_used == kMaxCentroids) throw std::logic_error("marching cubes table: too many centroids");
        for (int k = 0; k < len; ++k) centroids[mask][nc_used] |= static_cast<std::uint16_t>(1u << loop[k]);
        for (int k = 0; k < len; ++k) {
          out[w++] = static_cast<std::int8_t>(12 + nc_used);
          out[w++] = static_cast<std::int8_t>(loop[k]);
          out[w++] = static_cast<std::int8_t>(loop[(k + 1) % len]);
        }
        ++nc_used;
      }
    }
    out[w] = -1;
  }
};

const Table& table() {
  static const Table t;
  return t;
}

}  // namespace

int edgeAxis(int e) { return e / 4; }
int edgeLowerCorner(int e) { return kEdgeLo[e]; }

const std::int8_t* caseTriangles(int inside_mask) { return table().tris[inside_mask & 255].data(); }

std::uint16_t centroidEdges(int inside_mask, int j) { return table().centroids[inside_mask & 255][j]; }

TriangleMesh marchingCubesGrid(const std::vector<float>& values, int nx, int ny, int nz, float spacing) {
  if (nx < 0 || ny < 0 || nz < 0 || values.size() != static_cast<std::size_t>(nx) * ny * nz)
    throw std::invalid_argument("marchingCubesGrid: values.size() != nx * ny * nz");
  TriangleMesh mesh;
  std::unordered_map<std::int64_t, int> index;  // (grid point, axis) -> vertex
  auto at = [&](int x, int y, int z) {
    return values[static_cast<std::size_t>(x) + nx * (y + static_cast<std::size_t>(ny) * z)];
  };
  for (int z = 0; z + 1 < nz; ++z)
    for (int y = 0; y + 1 < ny; ++y)
      for (int x = 0; x + 1 < nx; ++x) {
        float v[8];
        int mask = 0;
        for (int c = 0; c < 8; ++c) {
          v[c] = at(x + (c & 1), y + ((c >> 1) & 1), z + ((c >> 2) & 1));
          if (v[c] < 0.0f) mask |= 1 << c;
        }
        if (mask == 0 || mask == 255) continue;
        int vid[12 + kMaxCentroids];
        Eigen::Vector3f pos[12];
        for (int e = 0; e < 12 + kMaxCentroids; ++e) vid[e] = -1;
        auto edge_vertex = [&](int e) {
          if (vid[e] >= 0) return;
          const int lo = kEdgeLo[e], hi = lo | (1 << (e / 4));
          const int gx = x + (lo & 1), gy = y + ((lo >> 1) & 1), gz = z + ((lo >> 2) & 1);
          const std::int64_t key =
              3 * (static_cast<std::int64_t>(gx) + nx * (gy + static_cast<std::int64_t>(ny) * gz)) + e / 4;
          const float s = v[lo] / (v[lo] - v[hi]);
          pos[e] = Eigen::Vector3f(static_cast<float>(gx), static_cast<float>(gy), static_cast<float>(gz));
          pos[e][e / 4] += s;
          pos[e] *= spacing;
          const auto [it, inserted] = index.emplace(key, static_cast<int>(mesh.vertices.size()));
          if (inserted) mesh.vertices.push_back(pos[e]);
          vid[e] = it->second;
        };
        for (const std::int8_t* t = caseTriangles(mask); *t >= 0; t += 3) {
          Eigen::Vector3i f;
          for (int k = 0; k < 3; ++k) {
            const int e = static_cast<std::uint8_t>(t[k]);  // >= 0 in a triangle; -1 only ends the list
            if (e >= 12 && vid[e] < 0) {                    // centroid of a loop: owned by this cube
              const std::uint16_t edges = centroidEdges(mask, e - 12);
              Eigen::Vector3f sum = Eigen::Vector3f::Zero();
              int cnt = 0;
              for (int q = 0; q < 12; ++q)
                if (edges & (1u << q)) edge_vertex(q), sum += pos[q], ++cnt;
              vid[e] = static_cast<int>(mesh.vertices.size());
              mesh.vertices.push_back(sum / static_cast<float>(cnt));
            } else if (e < 12) {
              edge_vertex(e);
            }
            f[k] = vid[e];
          }
          mesh.faces.push_back(f);
        }
      }
  return mesh;
}

}  // namespace vitamin_e::fusion::mc
