// TsdfVolume: configuration, mesh rasterisation and projective integration.
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "tsdf_impl.h"
#include "vitamin_e/common/rounding.h"

namespace vitamin_e::fusion {

using common::roundHalfAway;

namespace {
constexpr int kMaxAutoRasterDownscale = 8;
double sq(double x) { return x * x; }
void require(bool ok, const char* key, const std::string& what) {
  if (!ok) throw std::invalid_argument(std::string("tsdf.") + key + ": " + what);
}

// The image of a depth map downscaled by s (pixel centres at integer coordinates).
meshing::PinholeImage scaled(const meshing::PinholeImage& image, int s) {
  if (s == 1) return image;
  return {image.K.binned(s, s), (image.width + s - 1) / s, (image.height + s - 1) / s};
}

// Z-buffered rasterisation of the mesh into an inverse-depth image of size (w, h);
// uv are scaled by `scale` first. Inverse depth is affine over a planar triangle
// in the image, so linear interpolation is exact for planar faces. With `triangle`,
// also the index of the triangle seen at each pixel (-1: none).
std::vector<float> rasterize(const meshing::FrameMesh& mesh, double scale, double offset, int w, int h,
                             std::vector<int>* triangle = nullptr) {
  std::vector<float> inv(static_cast<std::size_t>(w) * h, 0.0f);
  if (triangle) triangle->assign(inv.size(), -1);
  std::vector<Eigen::Vector2d> uv(mesh.vertices.size());
  for (std::size_t i = 0; i < uv.size(); ++i) uv[i] = (mesh.vertices[i].uv.array() + offset) * scale - offset;
  for (std::size_t k = 0; k < mesh.triangles.size(); ++k) {
    const Eigen::Vector3i& t = mesh.triangles[k];
    const Eigen::Vector2d& a = uv[t[0]];
    const Eigen::Vector2d& b = uv[t[1]];
    const Eigen::Vector2d& c = uv[t[2]];
    const double area = (b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x());
    if (std::abs(area) < 1e-12) continue;
    const double za = mesh.vertices[t[0]].inv_depth, zb = mesh.vertices[t[1]].inv_depth,
                 zc = mesh.vertices[t[2]].inv_depth;
    const int x0 = std::max(0, static_cast<int>(std::ceil(std::min({a.x(), b.x(), c.x()}))));
    const int x1 = std::min(w - 1, static_cast<int>(std::floor(std::max({a.x(), b.x(), c.x()}))));
    const int y0 = std::max(0, static_cast<int>(std::ceil(std::min({a.y(), b.y(), c.y()}))));
    const int y1 = std::min(h - 1, static_cast<int>(std::floor(std::max({a.y(), b.y(), c.y()}))));
    const double inv_area = 1.0 / area;
    const double eps = -1e-9;
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        // Barycentric weights of (x, y).
        const double l0 = ((b.x() - x) * (c.y() - y) - (b.y() - y) * (c.x() - x)) * inv_area;
        const double l1 = ((c.x() - x) * (a.y() - y) - (c.y() - y) * (a.x() - x)) * inv_area;
        const double l2 = 1.0 - l0 - l1;
        if (l0 < eps || l1 < eps || l2 < eps) continue;
        const float z = static_cast<float>(l0 * za + l1 * zb + l2 * zc);
        const std::size_t at = static_cast<std::size_t>(y) * w + x;
        if (z > inv[at]) {
          inv[at] = z;
          if (triangle) (*triangle)[at] = static_cast<int>(k);
        }
      }
    }
  }
  return inv;
}

// The raster's downscale for a voxel of vs_map (map units): a voxel at the mesh's far depth
// (the 90th percentile of its vertices', at most max_depth_map) covers fx * vs / z pixels, and a
// raster pixel of half that picks each voxel's triangle to within a quarter of a voxel.
// A finer raster only repeats the same triangles (the depth itself comes from the plane).
int rasterScaleFor(const meshing::FrameMesh& mesh, const camera::Pinhole& K, double vs_map, double max_depth_map) {
  std::vector<double> z;
  z.reserve(mesh.vertices.size());
  for (const auto& v : mesh.vertices)
    if (v.inv_depth > 0.0 && std::isfinite(v.inv_depth)) z.push_back(1.0 / v.inv_depth);
  if (z.empty()) return 1;
  const auto far = z.begin() + static_cast<std::ptrdiff_t>(z.size() * 9 / 10);
  std::nth_element(z.begin(), far, z.end());
  const double z_far = std::min(*far, max_depth_map);
  const double footprint_px = std::min(K.fx, K.fy) * vs_map / z_far;
  return std::clamp(static_cast<int>(std::floor(0.5 * footprint_px)), 1, kMaxAutoRasterDownscale);
}
}  // namespace

void TsdfConfig::validate() const {
  require(voxel_size > 0.0, "voxel_size", "must be > 0");
  require(truncation >= voxel_size, "truncation", "must be >= voxel_size");
  require(max_weight >= 1.0, "max_weight", "must be >= 1");
  require(block_voxels >= 2 && block_voxels <= 64, "block_voxels", "must be in [2, 64]");
  require(min_depth > 0.0, "min_depth", "must be > 0");
  require(max_depth > min_depth, "max_depth", "must be > min_depth");
  require(min_extract_weight > 0.0, "min_extract_weight", "must be > 0");
  require(weight_depth_ref >= 0.0, "weight_depth_ref", "must be >= 0");
  require(raster_downscale >= 0 && raster_downscale <= 16, "raster_downscale", "must be in [0, 16]");
}

TsdfVolume::TsdfVolume(const TsdfConfig& config) : impl_(std::make_unique<Impl>()) {
  config.validate();
  impl_->config = config;
}
TsdfVolume::~TsdfVolume() = default;
TsdfVolume::TsdfVolume(TsdfVolume&&) noexcept = default;
TsdfVolume& TsdfVolume::operator=(TsdfVolume&&) noexcept = default;

const TsdfConfig& TsdfVolume::config() const { return impl_->config; }
std::size_t TsdfVolume::numBlocks() const { return impl_->blocks.size(); }
std::size_t TsdfVolume::lastRemeshedBlocks() const { return impl_->last_remeshed; }
void TsdfVolume::clear() {
  impl_->blocks.clear();
  impl_->changed.clear();
  impl_->replace_all = true;
  impl_->scaling = MapScaling{};
}

const MapScaling& TsdfVolume::scaling() const { return impl_->scaling; }

void TsdfVolume::setScaling(const MapScaling& volume_to_map) {
  if (!volume_to_map.isValid())
    throw std::invalid_argument("TsdfVolume::setScaling: a non-finite or non-positive scale");
  if (volume_to_map == impl_->scaling) return;
  impl_->scaling = volume_to_map;
  // Every surface moved: each block that has one (or had one, as reported) changed.
  for (const auto& [key, block] : impl_->blocks) {
    if (!block->triangles.empty() || block->reported) impl_->changed.insert(key);
  }
}

void TsdfVolume::rescale(const Eigen::Vector3d& centre, double factor) {
  setScaling(MapScaling::about(centre, factor).after(impl_->scaling));
}

std::vector<float> TsdfVolume::rasterizeDepth(const meshing::FrameMesh& mesh, const meshing::PinholeImage& image) {
  std::vector<float> d = rasterize(mesh, 1.0, 0.0, image.width, image.height);
  for (float& v : d) v = v > 0.0f ? 1.0f / v : 0.0f;
  return d;
}

IntegrationStats TsdfVolume::integrate(const meshing::FrameMesh& mesh, const Eigen::Isometry3d& T_w_c,
                                       const meshing::PinholeImage& image) {
  image.validate();
  const TsdfConfig& cfg = impl_->config;
  MeshRaster raster;
  raster.s = cfg.raster_downscale > 0 ? cfg.raster_downscale
                                      : rasterScaleFor(mesh, image.K, cfg.voxel_size * impl_->scaling.scale,
                                                       cfg.max_depth);  // the voxel in map units, as max_depth
  const meshing::PinholeImage small = scaled(image, raster.s);
  raster.width = small.width;
  raster.height = small.height;
  const bool full_size = raster.s == 1;
  std::vector<float> d =
      rasterize(mesh, 1.0 / raster.s, 0.5, small.width, small.height, full_size ? nullptr : &raster.triangle);
  for (float& v : d) v = v > 0.0f ? 1.0f / v : 0.0f;
  IntegrationStats stats;
  if (full_size) {
    // At full size the raster is the depth map itself: a voxel reads its nearest pixel (within half a
    // pixel of its projection), one array instead of the triangle ids and the planes.
    stats = impl_->fuse(d, small, nullptr, image, T_w_c);
    stats.raster_downscale = 1;
    return stats;
  }
  raster.planes.resize(mesh.triangles.size());
  for (std::size_t k = 0; k < mesh.triangles.size(); ++k) {
    const Eigen::Vector3i& t = mesh.triangles[k];
    const meshing::MeshVertex &a = mesh.vertices[t[0]], &b = mesh.vertices[t[1]], &c = mesh.vertices[t[2]];
    const Eigen::Vector2d e1 = b.uv - a.uv, e2 = c.uv - a.uv;
    const double d1 = b.inv_depth - a.inv_depth, d2 = c.inv_depth - a.inv_depth;
    const double det = e1.x() * e2.y() - e1.y() * e2.x();
    MeshRaster::Plane& plane = raster.planes[k];
    plane.u0 = a.uv.x();
    plane.v0 = a.uv.y();
    plane.inv0 = a.inv_depth;
    if (det != 0.0) {
      plane.du = (d1 * e2.y() - d2 * e1.y()) / det;
      plane.dv = (d2 * e1.x() - d1 * e2.x()) / det;
    }
  }
  stats = impl_->fuse(d, small, &raster, image, T_w_c);
  stats.raster_downscale = raster.s;
  return stats;
}

IntegrationStats TsdfVolume::integrateDepth(const std::vector<float>& depth_map, const Eigen::Isometry3d& T_map_c,
                                            const meshing::PinholeImage& image) {
  image.validate();
  if (depth_map.size() != static_cast<std::size_t>(image.width) * image.height)
    throw std::invalid_argument("TsdfVolume::integrateDepth: depth size != width * height");
  return impl_->fuse(depth_map, image, nullptr, image, T_map_c);
}

IntegrationStats TsdfVolume::Impl::fuse(const std::vector<float>& depth_map, const meshing::PinholeImage& depth_image,
                                        const MeshRaster* mesh, const meshing::PinholeImage& image,
                                        const Eigen::Isometry3d& T_map_c) {
  // Fused in the volume's frame: the camera's position and the depths scaled
  // back by the map's scaling, the depth limits (map units) with them.
  TsdfConfig cfg = config;
  Eigen::Isometry3d T_w_c = T_map_c;
  std::vector<float> scaled_depth;
  double to_volume_scale = 1.0;
  if (!scaling.isIdentity()) {
    const MapScaling to_volume = scaling.inverse();
    to_volume_scale = to_volume.scale;
    T_w_c.translation() = to_volume.apply(T_map_c.translation());
    const float k = static_cast<float>(to_volume.scale);
    scaled_depth.resize(depth_map.size());
    for (std::size_t i = 0; i < depth_map.size(); ++i) scaled_depth[i] = depth_map[i] * k;
    cfg.min_depth *= to_volume.scale;
    cfg.max_depth *= to_volume.scale;
    cfg.weight_depth_ref *= to_volume.scale;
  }
  const std::vector<float>& depth = scaled_depth.empty() ? depth_map : scaled_depth;
  IntegrationStats stats;
  const int n = cfg.block_voxels;
  const double vs = cfg.voxel_size, bs = blockSize(), trunc = cfg.truncation;

  // 1. Blocks within the truncation band of some measured pixel.
  {
    const camera::Pinhole& K = depth_image.K;
    const int W = depth_image.width, H = depth_image.height;
    float max_d = 0.0f;
    for (float v : depth)
      if (v >= cfg.min_depth && v <= cfg.max_depth) {
        max_d = std::max(max_d, v);
        ++stats.pixels_with_depth;
      }
    if (stats.pixels_with_depth == 0) return stats;
    const int stride = std::clamp(static_cast<int>(bs * std::min(K.fx, K.fy) / (2.0 * max_d)), 1, 16);
    keys.clear();
    for (int y = 0; y < H; y += stride) {
      for (int x = 0; x < W; x += stride) {
        const float z = depth[static_cast<std::size_t>(y) * W + x];
        if (!(z >= cfg.min_depth && z <= cfg.max_depth)) continue;
        const Eigen::Vector3d ray = K.ray(Eigen::Vector2d(x, y));
        const double len = ray.norm();
        const double r0 = z * len - trunc, r1 = z * len + trunc;  // range along the unit ray
        const Eigen::Vector3d dir_w = T_w_c.linear() * (ray / len);
        const int steps = static_cast<int>(std::ceil((r1 - r0) / (0.5 * bs)));
        for (int i = 0; i <= steps; ++i) {
          const double r = std::min(r1, r0 + i * 0.5 * bs);
          const Eigen::Vector3d p = T_w_c.translation() + dir_w * r;
          keys.push_back(packIndex((p / bs).array().floor().cast<int>().matrix()));
        }
      }
    }
    std::sort(keys.begin(), keys.end());
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  }

  // 2. Projective update of every voxel of those blocks. The measured depth at a voxel's
  // projection: a depth map's nearest pixel, or a mesh's triangle plane at the projection itself
  // (the triangle from the raster's nearest pixel).
  const camera::Pinhole& K = mesh ? image.K : depth_image.K;
  const int W = mesh ? image.width : depth_image.width, H = mesh ? image.height : depth_image.height;
  const double inv_s = mesh ? 1.0 / mesh->s : 1.0;
  const Eigen::Isometry3d T_c_w = T_w_c.inverse();
  const Eigen::Matrix3d R = T_c_w.linear();
  const Eigen::Vector3d dx = R.col(0) * vs, dy = R.col(1) * vs, dz = R.col(2) * vs;
  const float max_w = static_cast<float>(cfg.max_weight);
  for (std::uint64_t key : keys) {
    const Eigen::Vector3i b = unpackIndex(key);
    auto& slot = blocks[key];
    bool fresh = false;
    if (!slot) {
      slot = std::make_unique<Block>();
      slot->voxels.resize(static_cast<std::size_t>(n) * n * n);
      fresh = true;
    }
    Block& block = *slot;
    const Eigen::Vector3d origin_w = ((b * n).cast<double>().array() + 0.5).matrix() * vs;
    const Eigen::Vector3d origin_c = T_c_w * origin_w;
    std::size_t updated = 0;
    for (int iz = 0; iz < n; ++iz) {
      for (int iy = 0; iy < n; ++iy) {
        Eigen::Vector3d p = origin_c + iy * dy + iz * dz;
        Voxel* vox = &block.voxels[static_cast<std::size_t>(n) * (iy + n * iz)];
        for (int ix = 0; ix < n; ++ix, p += dx, ++vox) {
          if (p.z() < cfg.min_depth) continue;
          const double inv_z = 1.0 / p.z();
          const Eigen::Vector2d uv = K.projectPoint(p);
          // The nearest pixel must be in the image: lround(x) in [0, W) <=> x in (-0.5, W - 0.5).
          if (!(uv.x() > -0.5 && uv.x() < W - 0.5 && uv.y() > -0.5 && uv.y() < H - 0.5)) continue;
          float zm;
          if (mesh) {
            // The raster pixel nearest to uv (pixel centres at (s u + (s - 1) / 2)): in range, as uv is.
            const int u = roundHalfAway((uv.x() + 0.5) * inv_s - 0.5);
            const int v = roundHalfAway((uv.y() + 0.5) * inv_s - 0.5);
            const int t = mesh->triangle[static_cast<std::size_t>(v) * mesh->width + u];
            if (t < 0) continue;
            const MeshRaster::Plane& plane = mesh->planes[static_cast<std::size_t>(t)];
            const double inv = plane.inv0 + plane.du * (uv.x() - plane.u0) + plane.dv * (uv.y() - plane.v0);
            if (!(inv > 0.0)) continue;
            zm = static_cast<float>(to_volume_scale / inv);
          } else {
            const int u = roundHalfAway(uv.x());
            const int v = roundHalfAway(uv.y());
            zm = depth[static_cast<std::size_t>(v) * W + u];
          }
          if (!(zm >= cfg.min_depth && zm <= cfg.max_depth)) continue;
          // Signed distance along the ray (positive in front of the surface).
          const double sdf = (zm - p.z()) * p.norm() * inv_z;
          if (sdf < -trunc) continue;
          const float f = static_cast<float>(std::min(sdf, trunc));
          const float w = vox->weight;
          const float m =
              cfg.weight_depth_ref > 0.0 ? static_cast<float>(std::min(1.0, sq(cfg.weight_depth_ref / zm))) : 1.0f;
          vox->sdf = (vox->sdf * w + m * f) / (w + m);
          vox->weight = std::min(w + m, max_w);
          ++updated;
        }
      }
    }
    if (updated > 0) block.dirty = true;
    if (fresh && updated == 0) {
      blocks.erase(key);
      continue;
    }
    stats.blocks_allocated += fresh;
    ++stats.blocks_touched;
    stats.voxels_updated += updated;
  }
  return stats;
}

const Voxel* TsdfVolume::voxelAt(const Eigen::Vector3d& p_map) const {
  const Eigen::Vector3d p_w = impl_->scaling.isIdentity() ? p_map : impl_->scaling.inverse().apply(p_map);
  const int n = impl_->config.block_voxels;
  const Eigen::Vector3i g = (p_w / impl_->config.voxel_size).array().floor().cast<int>();
  const Eigen::Vector3i b(static_cast<int>(std::floor(static_cast<double>(g.x()) / n)),
                          static_cast<int>(std::floor(static_cast<double>(g.y()) / n)),
                          static_cast<int>(std::floor(static_cast<double>(g.z()) / n)));
  const Block* block = impl_->find(b);
  if (!block) return nullptr;
  const Eigen::Vector3i l = g - b * n;
  const int i = l.x() + n * (l.y() + n * l.z());
  return &block->voxels[static_cast<std::size_t>(i)];
}

bool TsdfVolume::sdfAt(const Eigen::Vector3d& p_w, double* sdf) const {
  const Voxel* v = voxelAt(p_w);
  if (!v || v->weight <= 0.0f) return false;
  *sdf = v->sdf * impl_->scaling.scale;
  return true;
}

void TsdfVolume::forEachVoxel(const std::function<void(const Eigen::Vector3d&, const Voxel&)>& fn) const {
  const int n = impl_->config.block_voxels;
  const double vs = impl_->config.voxel_size;
  for (const auto& [key, block] : impl_->blocks) {
    const Eigen::Vector3i b = unpackIndex(key);
    for (int z = 0; z < n; ++z)
      for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
          const int i = x + n * (y + n * z);
          const Voxel& v = block->voxels[static_cast<std::size_t>(i)];
          if (v.weight <= 0.0f) continue;
          const Eigen::Vector3d p_v = ((b * n + Eigen::Vector3i(x, y, z)).cast<double>().array() + 0.5).matrix() * vs;
          fn(impl_->scaling.apply(p_v), v);
        }
  }
}

}  // namespace vitamin_e::fusion
