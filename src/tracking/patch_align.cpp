#include "vitamin_e/tracking/patch_align.h"

#include <Eigen/Dense>
#include <cmath>

namespace vitamin_e::tracking {
namespace {

constexpr int kMaxRadius = 4;
constexpr int kMaxSide = 2 * kMaxRadius + 3;  // template plus a 1-px ring for its gradients

// Samples the n x n grid img(x0 + i, y0 + j), i, j in [0, n), at one shared
// fractional offset (one set of bilinear weights). False if it leaves the image.
bool sampleGrid(const cv::Mat& img, float x0, float y0, int n, float* out) {
  const float fx = std::floor(x0), fy = std::floor(y0);
  const int ix = static_cast<int>(fx), iy = static_cast<int>(fy);
  if (ix < 0 || iy < 0 || ix + n >= img.cols || iy + n >= img.rows) return false;
  const float ax = x0 - fx, ay = y0 - fy;
  const float w00 = (1 - ax) * (1 - ay), w01 = ax * (1 - ay), w10 = (1 - ax) * ay, w11 = ax * ay;
  for (int j = 0; j < n; ++j) {
    const float* r0 = img.ptr<float>(iy + j) + ix;
    const float* r1 = img.ptr<float>(iy + j + 1) + ix;
    for (int i = 0; i < n; ++i) out[j * n + i] = w00 * r0[i] + w01 * r0[i + 1] + w10 * r1[i] + w11 * r1[i + 1];
  }
  return true;
}

}  // namespace

bool alignPatch(const cv::Mat& prev, const cv::Mat& cur, const Eigen::Vector2f& p0, const PatchAlignParams& params,
                Eigen::Vector2f* p, float* gain) {
  const int r = params.radius;
  if (r < 1 || r > kMaxRadius || params.iterations < 1) return false;
  if (prev.type() != CV_32FC1 || cur.type() != CV_32FC1) return false;
  const int n = 2 * r + 1, m = n + 2;
  float grid[kMaxSide * kMaxSide];
  if (!sampleGrid(prev, p0.x() - static_cast<float>(r) - 1, p0.y() - static_cast<float>(r) - 1, m, grid)) return false;
  // Template, its zero-mean gradients and the 2x2 normal matrix.
  float T[kMaxSide * kMaxSide], gx[kMaxSide * kMaxSide], gy[kMaxSide * kMaxSide];
  float mt = 0, mgx = 0, mgy = 0;
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const float* c = grid + std::ptrdiff_t{j + 1} * m + (i + 1);
      const int k = j * n + i;
      T[k] = c[0];
      gx[k] = 0.5f * (c[1] - c[-1]);
      gy[k] = 0.5f * (c[m] - c[-m]);
      mt += T[k];
      mgx += gx[k];
      mgy += gy[k];
    }
  }
  const int N = n * n;
  mt /= static_cast<float>(N);
  mgx /= static_cast<float>(N);
  mgy /= static_cast<float>(N);
  float hxx = 0, hxy = 0, hyy = 0, stt = 0, stx = 0, sty = 0;
  for (int k = 0; k < N; ++k) {
    T[k] -= mt;
    gx[k] -= mgx;
    gy[k] -= mgy;
    hxx += gx[k] * gx[k];
    hxy += gx[k] * gy[k];
    hyy += gy[k] * gy[k];
    stt += T[k] * T[k];
    stx += T[k] * gx[k];
    sty += T[k] * gy[k];
  }
  const float det = hxx * hyy - hxy * hxy;
  const float tr = hxx + hyy;
  if (!(det > 1e-6f * tr * tr) || !(tr > 0.f)) return false;
  // With the gain: cur - mean = a (T + J d) is linear in (a, a dx, a dy); its
  // 3x3 normal matrix depends on the template only.
  Eigen::Matrix3f Minv = Eigen::Matrix3f::Zero();
  if (params.compensate_gain) {
    Eigen::Matrix3f M;
    M << stt, stx, sty, stx, hxx, hxy, sty, hxy, hyy;
    const float mdet = M.determinant();
    if (!(mdet > 1e-6f * det * stt)) return false;  // contrast explained by the shift alone
    Minv = M.inverse();
  }
  const Eigen::Vector2f start = *p;
  Eigen::Vector2f q = start;
  float I[kMaxSide * kMaxSide];
  float a = 1.f;
  for (int it = 0; it < params.iterations; ++it) {
    if (!sampleGrid(cur, q.x() - static_cast<float>(r), q.y() - static_cast<float>(r), n, I)) return false;
    float mi = 0;
    for (int k = 0; k < N; ++k) mi += I[k];
    mi /= static_cast<float>(N);
    float dx, dy;
    if (params.compensate_gain) {
      Eigen::Vector3f rhs = Eigen::Vector3f::Zero();
      for (int k = 0; k < N; ++k) {
        const float e = I[k] - mi;
        rhs += Eigen::Vector3f(T[k], gx[k], gy[k]) * e;
      }
      const Eigen::Vector3f x = Minv * rhs;
      a = x[0];
      if (!(a >= 0.25f && a <= 4.f)) return false;  // lost or inverted contrast
      dx = x[1] / a;
      dy = x[2] / a;
    } else {
      float bx = 0, by = 0;
      for (int k = 0; k < N; ++k) {
        const float e = (I[k] - mi) - T[k];
        bx += gx[k] * e;
        by += gy[k] * e;
      }
      dx = (hyy * bx - hxy * by) / det;
      dy = (hxx * by - hxy * bx) / det;
    }
    // Inverse compositional: the template moved by d explains the residual; the
    // match in `cur` is therefore at q - d.
    q -= Eigen::Vector2f(dx, dy);
    if ((q - start).squaredNorm() > params.max_shift * params.max_shift) return false;
    if (dx * dx + dy * dy < 1e-4f) break;
  }
  *p = q;
  if (gain) *gain = a;
  return true;
}

}  // namespace vitamin_e::tracking
