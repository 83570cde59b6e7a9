#include "vitamin_e/synth/renderer.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>

namespace vitamin_e::synth {

Renderer::Renderer(const Scene& scene, const camera::Camera& camera, int supersample)
    : scene_(scene), camera_(camera), ss_(supersample) {
  if (!camera_.valid()) throw std::invalid_argument("renderer: invalid camera");
  if (ss_ < 1 || ss_ > 4) throw std::invalid_argument("renderer: supersample must be in [1, 4]");
  const int w = camera_.width(), h = camera_.height();
  rays_c_.resize(static_cast<std::size_t>(w) * h * ss_ * ss_);
  std::vector<Eigen::Vector3d> centre(static_cast<std::size_t>(w) * h);
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      Eigen::Vector3d b;
      if (!camera_.unproject(Eigen::Vector2d(u, v), &b))
        throw std::invalid_argument("renderer: cannot unproject pixel (" + std::to_string(u) + ", " +
                                    std::to_string(v) + ")");
      centre[static_cast<std::size_t>(v) * w + u] = b;
      for (int i = 0; i < ss_; ++i) {
        for (int j = 0; j < ss_; ++j) {
          const Eigen::Vector2d uv(u + (j + 0.5) / ss_ - 0.5, v + (i + 0.5) / ss_ - 0.5);
          Eigen::Vector3d bs = b;
          if (ss_ > 1 && !camera_.unproject(uv, &bs)) bs = b;
          rays_c_[(static_cast<std::size_t>(v) * w + u) * ss_ * ss_ + static_cast<std::size_t>(i) * ss_ + j] =
              bs.normalized().cast<float>();
        }
      }
    }
  }
  // Per tile, a square pyramid around the cone of its rays (axis: their mean,
  // half-angle: the widest of them plus a margin): each frame, only the boxes
  // that may meet it are tested by the tile's pixels.
  tiles_x_ = (w + kTile - 1) / kTile;
  const int tiles_y = (h + kTile - 1) / kTile;
  tile_normals_c_.resize(static_cast<std::size_t>(tiles_x_) * tiles_y);
  for (int ty = 0; ty < tiles_y; ++ty) {
    for (int tx = 0; tx < tiles_x_; ++tx) {
      Eigen::Vector3d axis = Eigen::Vector3d::Zero();
      const int n = ss_ * ss_;
      auto for_rays = [&](auto&& fn) {
        for (int v = ty * kTile; v < std::min(h, (ty + 1) * kTile); ++v)
          for (int u = tx * kTile; u < std::min(w, (tx + 1) * kTile); ++u)
            for (int k = 0; k < n; ++k)
              fn(rays_c_[(static_cast<std::size_t>(v) * w + u) * n + k].template cast<double>());
      };
      for_rays([&](const Eigen::Vector3d& r) { axis += r; });
      axis.normalize();
      double cos_max = 1.0;
      for_rays([&](const Eigen::Vector3d& r) { cos_max = std::min(cos_max, axis.dot(r.normalized())); });
      const double half = std::acos(std::clamp(cos_max, -1.0, 1.0)) + 1e-4;
      auto& normals = tile_normals_c_[static_cast<std::size_t>(ty) * tiles_x_ + tx];
      if (half >= 0.5 * M_PI - 1e-3) {
        // Wider than a half space (not for a real tile): planes that keep everything.
        for (auto& nrm : normals) nrm.setZero();
        continue;
      }
      const Eigen::Vector3d e1 = axis.unitOrthogonal(), e2 = axis.cross(e1);
      // The plane tangent to the cone on the side of e, normal pointing inside.
      normals[0] = std::sin(half) * axis - std::cos(half) * e1;
      normals[1] = std::sin(half) * axis + std::cos(half) * e1;
      normals[2] = std::sin(half) * axis - std::cos(half) * e2;
      normals[3] = std::sin(half) * axis + std::cos(half) * e2;
    }
  }
  // Angular size of a pixel (of a subsample when supersampling) from the
  // neighbouring centre rays: the distortion makes it vary over the image.
  pixel_angle_.resize(centre.size());
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const Eigen::Vector3d& b = centre[static_cast<std::size_t>(v) * w + u];
      const Eigen::Vector3d& bx = centre[static_cast<std::size_t>(v) * w + (u + 1 < w ? u + 1 : u - 1)];
      const Eigen::Vector3d& by = centre[static_cast<std::size_t>(v + 1 < h ? v + 1 : v - 1) * w + u];
      const double ax = std::acos(std::clamp(b.normalized().dot(bx.normalized()), -1.0, 1.0));
      const double ay = std::acos(std::clamp(b.normalized().dot(by.normalized()), -1.0, 1.0));
      pixel_angle_[static_cast<std::size_t>(v) * w + u] = static_cast<float>(std::sqrt(ax * ay) / ss_);
    }
  }
}

cv::Mat Renderer::renderFloat(const Eigen::Isometry3d& T_w_c, cv::Mat* depth) const {
  const int w = camera_.width(), h = camera_.height(), n = ss_ * ss_;
  cv::Mat img(h, w, CV_32FC1);
  if (depth) depth->create(h, w, CV_32FC1);
  const Eigen::Matrix3d R = T_w_c.linear();
  const Eigen::Vector3d o = T_w_c.translation();
  RayHit hit;
  const float sky = scene_.skyIntensity();
  std::vector<int> boxes;
  std::vector<double> box_dist;
  // A room keeps the index order of its boxes (its images stay bit for bit as
  // they were); open scenes test their many boxes nearest first.
  const bool nearest_first = !scene_.hasRoom();
  std::array<Eigen::Vector3d, 4> normals_w;
  // 16 x 16 tiles: neighbouring pixels read neighbouring texels, so tiles keep
  // the texture reads in cache (rows sweep whole walls).
  for (int tv = 0; tv < h; tv += kTile) {
    for (int tu = 0; tu < w; tu += kTile) {
      const auto& normals_c = tile_normals_c_[static_cast<std::size_t>(tv / kTile) * tiles_x_ + tu / kTile];
      for (int k = 0; k < 4; ++k) normals_w[k] = R * normals_c[k];
      scene_.boxesInPyramid(o, normals_w, &boxes, nearest_first ? &box_dist : nullptr);
      for (int v = tv; v < std::min(h, tv + kTile); ++v) {
        float* row = img.ptr<float>(v);
        float* drow = depth ? depth->ptr<float>(v) : nullptr;
        for (int u = tu; u < std::min(w, tu + kTile); ++u) {
          const std::size_t pix = static_cast<std::size_t>(v) * w + u;
          const double ang = pixel_angle_[pix];
          float sum = 0.0f, zsum = 0.0f;
          int hits = 0;
          for (int k = 0; k < n; ++k) {
            const Eigen::Vector3f& rc = rays_c_[pix * n + k];
            const Eigen::Vector3d d = R * rc.cast<double>();
            if (nearest_first ? scene_.intersect(o, d, &hit, boxes, box_dist) : scene_.intersect(o, d, &hit, &boxes)) {
              const double footprint = hit.t * ang / std::sqrt(std::max(hit.cos_incidence, 0.05));
              sum += scene_.shade(hit, footprint);
              zsum += static_cast<float>(hit.t * rc.z());
              ++hits;
            }
          }
          // Rays that hit nothing see the flat sky (never in a room).
          if (hits < n) sum += sky * static_cast<float>(n - hits);
          row[u] = sum / static_cast<float>(n);
          if (drow) drow[u] = hits ? zsum / static_cast<float>(hits) : 0.0f;
        }
      }
    }
  }
  return img;
}

cv::Mat Renderer::render(const Eigen::Isometry3d& T_w_c, const RenderOptions& options, cv::Mat* depth) const {
  const cv::Mat f = renderFloat(T_w_c, depth);
  cv::Mat out(f.size(), CV_8UC1);
  cv::RNG rng(options.noise_seed ^ 0x9E3779B97F4A7C15ULL);
  const bool noisy = options.noise_sigma > 0.0;
  for (int v = 0; v < f.rows; ++v) {
    const float* in = f.ptr<float>(v);
    uchar* o = out.ptr<uchar>(v);
    for (int u = 0; u < f.cols; ++u) {
      double x = 255.0 * in[u];
      if (noisy) x += rng.gaussian(options.noise_sigma);
      o[u] = static_cast<uchar>(std::clamp(std::lround(x), 0L, 255L));
    }
  }
  return out;
}

}  // namespace vitamin_e::synth
