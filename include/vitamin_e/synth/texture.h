#pragma once
// Procedural surface textures for the synthetic sequences: deterministic from a
// seed, rich detail at several scales (value-noise octaves at non-harmonic
// wavelengths, hard-edged discs/rectangles/strokes at 1-40 cm), never periodic.
// Each texture keeps a mip pyramid (16-bit) for anti-aliased (trilinear) sampling.
#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

namespace vitamin_e::synth {

// splitmix64: a small, portable deterministic generator.
class Rng {
 public:
  explicit Rng(std::uint64_t seed) : state_(seed) {}
  std::uint64_t next();
  double uniform();                      // [0, 1)
  double uniform(double lo, double hi);  // [lo, hi)
  double gaussian();                     // N(0, 1)

 private:
  std::uint64_t state_;
};

// Mixes several numbers into one seed.
std::uint64_t mixSeed(std::uint64_t a, std::uint64_t b, std::uint64_t c = 0);

// A CV_32FC1 texture (values in [0, 1]) of width x height texels of texel_m
// metres, generated from seed.
cv::Mat generateProceduralTexture(int width, int height, double texel_m, std::uint64_t seed);

class Texture {
 public:
  Texture() = default;
  // Takes a CV_32FC1 level 0 (texel (i, j) covers [j, j+1) x [i, i+1) * texel_m)
  // and builds the pyramid.
  Texture(const cv::Mat& level0, double texel_m);

  int width() const { return levels_.empty() ? 0 : levels_[0].cols; }
  int height() const { return levels_.empty() ? 0 : levels_[0].rows; }
  double texelSize() const { return texel_m_; }
  int numLevels() const { return static_cast<int>(levels_.size()); }
  // Mip level l (CV_16UC1, value * 65535); level 0 is the input.
  const cv::Mat& level(int l) const { return levels_[l]; }

  // Bilinear at level 0; (u, v) in metres from the texture origin (clamped at the border).
  float sampleLevel0(double u_m, double v_m) const { return bilinear(0, u_m / texel_m_, v_m / texel_m_); }
  // Trilinear: the mip level whose texel matches footprint_m (the pixel's size on the surface).
  float sample(double u_m, double v_m, double footprint_m) const;

 private:
  float bilinear(int level, double x, double y) const;  // x, y in level-0 texel units
  std::vector<cv::Mat> levels_;
  double texel_m_ = 0.01;
};

}  // namespace vitamin_e::synth
