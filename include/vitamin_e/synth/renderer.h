#pragma once
// Renders a Scene through a camera model with its lens distortion: one ray per
// (sub)pixel through Camera::unproject, precomputed once; anti-aliased by mip
// filtering (per-pixel footprint from distance, incidence and the pixel's
// angular size) and optional s x s supersampling; optional Gaussian noise.
// Rays that hit nothing (open scenes) take the scene's flat sky intensity.
#include <array>
#include <cstdint>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "vitamin_e/camera/camera.h"
#include "vitamin_e/synth/scene.h"

namespace vitamin_e::synth {

struct RenderOptions {
  double noise_sigma = 0.0;  // Gaussian noise [grey levels of 255]
  std::uint64_t noise_seed = 0;
};

class Renderer {
 public:
  // Throws std::invalid_argument if the camera is invalid, supersample not in
  // [1, 4] or a pixel cannot be unprojected.
  Renderer(const Scene& scene, const camera::Camera& camera, int supersample = 1);

  // 8-bit grey image (CV_8UC1, camera size) seen from T_w_c; depth (optional,
  // CV_32FC1) receives the z of the surface at each pixel centre ray [m], 0 if none.
  cv::Mat render(const Eigen::Isometry3d& T_w_c, const RenderOptions& options = {}, cv::Mat* depth = nullptr) const;
  // Same, as float intensities in [0, 1], without noise or quantization.
  cv::Mat renderFloat(const Eigen::Isometry3d& T_w_c, cv::Mat* depth = nullptr) const;

  const camera::Camera& camera() const { return camera_; }
  int supersample() const { return ss_; }

 private:
  const Scene& scene_;
  camera::Camera camera_;
  int ss_ = 1;
  std::vector<Eigen::Vector3f> rays_c_;  // per subsample, row-major pixels then s*s samples; unit bearings
  std::vector<float> pixel_angle_;       // per pixel: angular size [rad] (of one subsample)
  static constexpr int kTile = 16;       // pixels are rendered in kTile x kTile tiles
  int tiles_x_ = 0;
  // Per tile (row-major): inward normals (camera frame) of a pyramid holding all its rays.
  std::vector<std::array<Eigen::Vector3d, 4>> tile_normals_c_;
};

}  // namespace vitamin_e::synth
