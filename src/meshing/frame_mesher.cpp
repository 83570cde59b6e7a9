#include "vitamin_e/meshing/frame_mesher.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "vitamin_e/meshing/delaunay.h"

namespace vitamin_e::meshing {

namespace {
void require(bool ok, const char* key, const std::string& what) {
  if (!ok) throw std::invalid_argument(std::string(key) + ": " + what);
}
}  // namespace

void PinholeImage::validate() const {
  require(std::isfinite(K.fx) && K.fx > 0.0, "fx", "must be > 0");
  require(std::isfinite(K.fy) && K.fy > 0.0, "fy", "must be > 0");
  require(std::isfinite(K.cx), "cx", "must be finite");
  require(std::isfinite(K.cy), "cy", "must be finite");
  require(width > 0, "width", "must be > 0");
  require(height > 0, "height", "must be > 0");
}

std::vector<std::pair<int, int>> FrameMesh::edges() const {
  // Bucketed by the smaller end (a counting sort), each bucket (a vertex's few larger
  // neighbours) sorted and deduplicated: the order of sorting all pairs, in linear time.
  const int n = static_cast<int>(vertices.size());
  std::vector<int> start(static_cast<std::size_t>(n) + 1, 0), larger(triangles.size() * 3);
  for (const auto& t : triangles)
    for (int k = 0; k < 3; ++k) ++start[std::min(t[k], t[(k + 1) % 3]) + 1];
  for (int i = 0; i < n; ++i) start[i + 1] += start[i];
  {
    std::vector<int> fill(start.begin(), start.end() - 1);
    for (const auto& t : triangles)
      for (int k = 0; k < 3; ++k) {
        const int a = t[k], b = t[(k + 1) % 3];
        larger[fill[std::min(a, b)]++] = std::max(a, b);
      }
  }
  std::vector<std::pair<int, int>> e;
  e.reserve(triangles.size() * 3 / 2 + 3);
  for (int a = 0; a < n; ++a) {
    const auto first = larger.begin() + start[a], last = larger.begin() + start[a + 1];
    std::sort(first, last);
    for (auto it = first; it != last; ++it)
      if (it == first || *it != *(it - 1)) e.emplace_back(a, *it);
  }
  return e;
}

void FrameMesherConfig::validate() const {
  require(max_edge_px > 0.0, "max_edge_px", "must be > 0");
  require(max_normal_angle_deg > 0.0 && max_normal_angle_deg <= 90.0, "max_normal_angle_deg", "must be in (0, 90]");
  require(max_inv_depth_jump > 0.0, "max_inv_depth_jump", "must be > 0");
  require(min_depth > 0.0, "min_depth", "must be > 0");
  require(max_depth > min_depth, "max_depth", "must be > min_depth");
}

FrameMesher::FrameMesher(const FrameMesherConfig& config) : config_(config) { config_.validate(); }

FrameMesh FrameMesher::build(const std::vector<std::uint64_t>& ids, const std::vector<Eigen::Vector2d>& uv,
                             const std::vector<double>& depth, const PinholeImage& image) const {
  if (ids.size() != uv.size() || uv.size() != depth.size())
    throw std::invalid_argument("FrameMesher::build: ids, uv and depth must have the same size");
  FrameMesh mesh;
  mesh.vertices.reserve(ids.size());
  std::vector<Eigen::Vector2d> pts;
  pts.reserve(ids.size());
  for (std::size_t i = 0; i < ids.size(); ++i) {
    const double z = depth[i];
    if (!std::isfinite(z) || z < config_.min_depth || z > config_.max_depth) continue;
    if (!std::isfinite(uv[i].x()) || !std::isfinite(uv[i].y()) || !image.inImage(uv[i])) continue;
    MeshVertex v;
    v.id = ids[i];
    v.uv = uv[i];
    v.inv_depth = v.measured_inv_depth = 1.0 / z;
    mesh.vertices.push_back(v);
    pts.push_back(uv[i]);
  }
  mesh.triangles = delaunayTriangulate(pts);
  prune(&mesh, image.K);
  return mesh;
}

FrameMesh FrameMesher::buildFromPoints(const std::vector<std::uint64_t>& ids, const std::vector<Eigen::Vector3d>& p_c,
                                       const PinholeImage& image) const {
  std::vector<Eigen::Vector2d> uv(p_c.size());
  std::vector<double> depth(p_c.size());
  for (std::size_t i = 0; i < p_c.size(); ++i) {
    depth[i] = p_c[i].z();
    uv[i] = p_c[i].z() > 0.0 ? image.K.projectPoint(p_c[i]) : Eigen::Vector2d(-1.0, -1.0);
  }
  return build(ids, uv, depth, image);
}

void FrameMesher::prune(FrameMesh* mesh, const camera::Pinhole& K) const {
  const double max_edge2 = config_.max_edge_px * config_.max_edge_px;
  const double min_cos = std::cos(config_.max_normal_angle_deg * M_PI / 180.0);
  auto& V = mesh->vertices;
  std::vector<Eigen::Vector3i> kept;
  kept.reserve(mesh->triangles.size());
  for (const auto& t : mesh->triangles) {
    const MeshVertex& a = V[t[0]];
    const MeshVertex& b = V[t[1]];
    const MeshVertex& c = V[t[2]];
    if ((a.uv - b.uv).squaredNorm() > max_edge2 || (b.uv - c.uv).squaredNorm() > max_edge2 ||
        (c.uv - a.uv).squaredNorm() > max_edge2)
      continue;
    const double lo = std::min({a.inv_depth, b.inv_depth, c.inv_depth});
    const double hi = std::max({a.inv_depth, b.inv_depth, c.inv_depth});
    if (!(lo > 0.0) || (hi - lo) > config_.max_inv_depth_jump * hi) continue;
    if (config_.jump_on_measured) {
      const double mlo = std::min({a.measured_inv_depth, b.measured_inv_depth, c.measured_inv_depth});
      const double mhi = std::max({a.measured_inv_depth, b.measured_inv_depth, c.measured_inv_depth});
      if ((mhi - mlo) > config_.max_inv_depth_jump * mhi) continue;
    }
    const Eigen::Vector3d pa = K.ray(a.uv) * (1.0 / a.inv_depth);
    const Eigen::Vector3d pb = K.ray(b.uv) * (1.0 / b.inv_depth);
    const Eigen::Vector3d pc = K.ray(c.uv) * (1.0 / c.inv_depth);
    const Eigen::Vector3d n = (pb - pa).cross(pc - pa);
    const Eigen::Vector3d ray = (pa + pb + pc) / 3.0;
    const double nn = n.norm() * ray.norm();
    if (!(nn > 0.0) || std::abs(n.dot(ray)) < min_cos * nn) continue;
    kept.push_back(t);
  }
  mesh->triangles = std::move(kept);
  if (!config_.drop_unused_vertices) return;
  std::vector<int> remap(V.size(), -1);
  for (const auto& t : mesh->triangles)
    for (int k = 0; k < 3; ++k) remap[t[k]] = 0;
  int next = 0;
  for (std::size_t i = 0; i < V.size(); ++i)
    if (remap[i] == 0) {
      remap[i] = next;
      V[next++] = V[i];
    }
  V.resize(next);
  for (auto& t : mesh->triangles)
    for (int k = 0; k < 3; ++k) t[k] = remap[t[k]];
}

}  // namespace vitamin_e::meshing
