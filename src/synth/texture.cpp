#include "vitamin_e/synth/texture.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include <opencv2/imgproc.hpp>

#include "texture_noise.h"

namespace vitamin_e::synth {

std::uint64_t Rng::next() {
  std::uint64_t z = (state_ += 0x9E3779B97F4A7C15ULL);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

double Rng::uniform() { return static_cast<double>(next() >> 11) * (1.0 / 9007199254740992.0); }

double Rng::uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }

double Rng::gaussian() {
  const double u1 = std::max(uniform(), 1e-300), u2 = uniform();
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
}

std::uint64_t mixSeed(std::uint64_t a, std::uint64_t b, std::uint64_t c) {
  Rng r(a * 0x9E3779B97F4A7C15ULL ^ (b + 0x632BE59BD9B4E019ULL) ^ (c * 0xD1B54A32D192ED03ULL));
  r.next();
  return r.next();
}

namespace detail {

// One octave of value noise with the given wavelength [texels]: random values on
// a lattice, bicubic interpolation, random sub-lattice offset. Added into dst.
void addValueNoise(cv::Mat* dst, double wavelength_px, double amplitude, Rng* rng) {
  const int gw = static_cast<int>(std::ceil(dst->cols / wavelength_px)) + 4;
  const int gh = static_cast<int>(std::ceil(dst->rows / wavelength_px)) + 4;
  cv::Mat grid(gh, gw, CV_32FC1);
  for (int i = 0; i < gh; ++i)
    for (int j = 0; j < gw; ++j) grid.at<float>(i, j) = static_cast<float>(rng->uniform(-1.0, 1.0));
  cv::Mat up;
  cv::resize(grid, up, cv::Size(static_cast<int>(gw * wavelength_px), static_cast<int>(gh * wavelength_px)), 0, 0,
             cv::INTER_CUBIC);
  const int ox =
      static_cast<int>(rng->uniform(wavelength_px, std::max(wavelength_px + 1.0, up.cols - dst->cols - wavelength_px)));
  const int oy =
      static_cast<int>(rng->uniform(wavelength_px, std::max(wavelength_px + 1.0, up.rows - dst->rows - wavelength_px)));
  const int x0 = std::clamp(ox, 0, up.cols - dst->cols), y0 = std::clamp(oy, 0, up.rows - dst->rows);
  cv::scaleAdd(up(cv::Rect(x0, y0, dst->cols, dst->rows)), amplitude, *dst, *dst);
}

// Hard-edged shapes of size in [min_m, max_m]: discs, rotated rectangles, strokes.
void addShapes(cv::Mat* dst, double texel_m, double min_m, double max_m, double per_m2, double amplitude, Rng* rng) {
  const double area = dst->cols * texel_m * dst->rows * texel_m;
  const int n = static_cast<int>(std::floor(per_m2 * area + 0.5));
  for (int k = 0; k < n; ++k) {
    const cv::Point2f c(static_cast<float>(rng->uniform(0, dst->cols)), static_cast<float>(rng->uniform(0, dst->rows)));
    // Log-uniform size: as many small shapes per octave of size as large ones.
    const double size_px = std::exp(rng->uniform(std::log(min_m), std::log(max_m))) / texel_m;
    const double value = amplitude * rng->uniform(-1.0, 1.0);
    const int kind = static_cast<int>(rng->uniform(0.0, 3.0));
    std::vector<cv::Point> poly;
    const double ang = rng->uniform(0.0, M_PI);
    const double aspect = kind == 2 ? rng->uniform(0.06, 0.2) : rng->uniform(0.3, 1.0);
    const double a = 0.5 * size_px, b = 0.5 * size_px * aspect;
    const int segments = kind == 0 ? 20 : 4;
    for (int s = 0; s < segments; ++s) {
      double x, y;
      if (kind == 0) {
        const double th = 2.0 * M_PI * s / segments;
        x = a * std::cos(th);
        y = b * std::sin(th);
      } else {
        x = (s == 0 || s == 3) ? -a : a;
        y = (s < 2) ? -b : b;
      }
      poly.emplace_back(static_cast<int>(c.x + x * std::cos(ang) - y * std::sin(ang)),
                        static_cast<int>(c.y + x * std::sin(ang) + y * std::cos(ang)));
    }
    // Add (not overwrite) so overlapping shapes keep both edges.
    const cv::Rect box = cv::boundingRect(poly) & cv::Rect(0, 0, dst->cols, dst->rows);
    if (box.area() <= 0) continue;
    cv::Mat mask = cv::Mat::zeros(box.size(), CV_8UC1);
    for (auto& p : poly) p -= box.tl();
    cv::fillConvexPoly(mask, poly, cv::Scalar(1));
    cv::Mat roi = (*dst)(box);
    cv::add(roi, cv::Scalar(value), roi, mask);
  }
}

}  // namespace detail

cv::Mat generateProceduralTexture(int width, int height, double texel_m, std::uint64_t seed) {
  CV_Assert(width > 0 && height > 0 && texel_m > 0.0);
  Rng rng(seed);
  cv::Mat tex = cv::Mat::zeros(height, width, CV_32FC1);
  // Value-noise octaves at wavelengths 1.3 m .. 1.5 cm with ratio 1.83 (not a
  // power of two, so lattices never line up), amplitude ~ wavelength^0.5.
  for (double lambda_m = 1.3; lambda_m >= 0.015; lambda_m /= 1.83) {
    const double px = lambda_m / texel_m;
    if (px < 2.0) break;
    detail::addValueNoise(&tex, px, 0.22 * std::pow(lambda_m / 1.3, 0.45), &rng);
  }
  // Shapes with hard edges: corners, blobs and strokes from 1.5 cm to 40 cm.
  detail::addShapes(&tex, texel_m, 0.015, 0.4, 60.0, 0.35, &rng);
  // Soften aliasing of the rasterized edges a little.
  cv::GaussianBlur(tex, tex, cv::Size(3, 3), 0.6);
  // Normalize to mean 0.5, std 0.17; a soft clip keeps the extremes.
  cv::Scalar mean, stddev;
  cv::meanStdDev(tex, mean, stddev);
  const double s = 0.17 / std::max(stddev[0], 1e-6);
  for (int i = 0; i < tex.rows; ++i) {
    float* row = tex.ptr<float>(i);
    for (int j = 0; j < tex.cols; ++j) {
      const double x = (row[j] - mean[0]) * s;
      row[j] = static_cast<float>(0.5 + 0.45 * std::tanh(x / 0.45));
    }
  }
  return tex;
}

Texture::Texture(const cv::Mat& level0, double texel_m) : texel_m_(texel_m) {
  CV_Assert(level0.type() == CV_32FC1 && !level0.empty() && texel_m > 0.0);
  cv::Mat cur = level0;
  for (;;) {
    // 16-bit storage: half the memory traffic of float, far below 8-bit output steps.
    cv::Mat q;
    cur.convertTo(q, CV_16UC1, 65535.0);
    levels_.push_back(q);
    if (cur.cols < 4 || cur.rows < 4 || levels_.size() >= 12) break;
    cv::Mat down;
    cv::pyrDown(cur, down);
    cur = down;
  }
}

float Texture::bilinear(int level, double x, double y) const {
  const cv::Mat& img = levels_[level];
  // pyrDown centres output texel k on input texel 2k, so texel k of level l is
  // centred at level-0 coordinate 2^l k + 0.5 (texel centres at +0.5).
  const float scale = 1.0f / static_cast<float>(1 << level);
  const float fx = std::clamp(static_cast<float>(x - 0.5) * scale, 0.0f, static_cast<float>(img.cols) - 1.001f);
  const float fy = std::clamp(static_cast<float>(y - 0.5) * scale, 0.0f, static_cast<float>(img.rows) - 1.001f);
  const int x0 = static_cast<int>(fx), y0 = static_cast<int>(fy);
  const float ax = fx - static_cast<float>(x0), ay = fy - static_cast<float>(y0);
  const std::uint16_t* r0 = img.ptr<std::uint16_t>(y0) + x0;
  const std::uint16_t* r1 = reinterpret_cast<const std::uint16_t*>(reinterpret_cast<const uchar*>(r0) + img.step[0]);
  const float a0 = r0[0], a1 = r0[1], b0 = r1[0], b1 = r1[1];
  const float top = a0 + ax * (a1 - a0);
  const float bot = b0 + ax * (b1 - b0);
  return (top + ay * (bot - top)) * (1.0f / 65535.0f);
}

namespace {
// log2 for mip selection: exponent plus a quadratic in the mantissa (error
// < 0.01), monotonic and continuous, much cheaper than std::log2.
inline float fastLog2(float v) {  // v > 0, normal
  std::uint32_t bits;
  std::memcpy(&bits, &v, sizeof(bits));
  const int e = static_cast<int>((bits >> 23) & 0xFF) - 127;
  bits = (bits & 0x007FFFFFu) | 0x3F800000u;  // mantissa in [1, 2)
  float m;
  std::memcpy(&m, &bits, sizeof(m));
  const float x = m - 1.0f;
  return static_cast<float>(e) + x * (1.3466f - 0.3466f * x);
}
}  // namespace

float Texture::sample(double u_m, double v_m, double footprint_m) const {
  const double inv = 1.0 / texel_m_;
  const double x = u_m * inv, y = v_m * inv;
  const float ratio = static_cast<float>(footprint_m * inv);
  if (ratio <= 1.0f) return bilinear(0, x, y);
  const float lod = fastLog2(ratio);
  const int max_level = numLevels() - 1;
  if (lod >= static_cast<float>(max_level)) return bilinear(max_level, x, y);
  const int l0 = static_cast<int>(lod);
  const float a = lod - static_cast<float>(l0);
  const float v0 = bilinear(l0, x, y);
  if (a < 1e-3f) return v0;
  return v0 + a * (bilinear(l0 + 1, x, y) - v0);
}

}  // namespace vitamin_e::synth
