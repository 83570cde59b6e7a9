#include "vitamin_e/tracking/curvature.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <opencv2/core/hal/intrin.hpp>
#include <opencv2/imgproc.hpp>

#include "tracker_internal.h"
#include "vitamin_e/common/rounding.h"

namespace vitamin_e::tracking {

void computeCurvature(const cv::Mat& gray, double sigma, cv::Mat* kappa, int stripes, cv::Mat* smoothed) {
  if (gray.empty() || (gray.type() != CV_8UC1 && gray.type() != CV_32FC1)) {
    throw std::invalid_argument("computeCurvature: gray must be CV_8UC1 or CV_32FC1");
  }
  cv::Mat f;
  gray.convertTo(f, CV_32F);
  if (sigma > 0.0) {
    const int k = 2 * static_cast<int>(std::ceil(2.5 * sigma)) + 1;
    cv::GaussianBlur(f, f, cv::Size(k, k), sigma, sigma, cv::BORDER_REFLECT101);
  }
  const int rows = f.rows, cols = f.cols;
  kappa->create(rows, cols, CV_32FC1);
  cv::Mat& K = *kappa;
  forStripes(rows, stripes, 64, [&](int r0, int r1) {
    for (int y = r0; y < r1; ++y) {
      float* out = K.ptr<float>(y);
      if (y == 0 || y == rows - 1 || cols < 3) {
        std::fill(out, out + cols, 0.f);
        continue;
      }
      const float* um = f.ptr<float>(y - 1);
      const float* u0 = f.ptr<float>(y);
      const float* up = f.ptr<float>(y + 1);
      out[0] = 0.f;
      out[cols - 1] = 0.f;
      for (int x = 1; x < cols - 1; ++x) {
        const float fx = 0.5f * (u0[x + 1] - u0[x - 1]);
        const float fy = 0.5f * (up[x] - um[x]);
        const float fxx = u0[x + 1] - 2.f * u0[x] + u0[x - 1];
        const float fyy = up[x] - 2.f * u0[x] + um[x];
        const float fxy = 0.25f * (up[x + 1] - up[x - 1] - um[x + 1] + um[x - 1]);
        out[x] = fy * fy * fxx - 2.f * fx * fy * fxy + fx * fx * fyy;
      }
    }
  });
  if (smoothed) *smoothed = f;
}

float robustCurvatureScale(const cv::Mat& kappa, int step) {
  std::vector<float> v;
  v.reserve(static_cast<size_t>(kappa.rows / step + 1) * (kappa.cols / step + 1));
  for (int y = 1; y < kappa.rows - 1; y += step) {
    const float* row = kappa.ptr<float>(y);
    for (int x = 1; x < kappa.cols - 1; x += step) {
      const float a = std::fabs(row[x]);
      if (a > 0.f) v.push_back(a);
    }
  }
  // Mostly-flat image: too few non-zero samples for a meaningful scale.
  if (v.size() < 16) return 0.f;
  auto mid = v.begin() + static_cast<long>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

void detectExtrema(const cv::Mat& kappa, int r, float threshold, int border, std::vector<Extremum>* out, int stripes) {
  out->clear();
  const int rows = kappa.rows, cols = kappa.cols;
  border = std::max(border, r + 1);
  if (rows <= 2 * border || cols <= 2 * border) return;
  threshold = std::max(threshold, 1e-12f);
  // Window maxima/minima by (SIMD) grey dilation/erosion; an extremum equals
  // its window's max (or min) and is the only pixel of the window that does.
  cv::Mat mx, mn;
  const cv::Mat se = cv::getStructuringElement(cv::MORPH_RECT, cv::Size(2 * r + 1, 2 * r + 1));
  cv::dilate(kappa, mx, se, cv::Point(-1, -1), 1, cv::BORDER_REPLICATE);
  cv::erode(kappa, mn, se, cv::Point(-1, -1), 1, cv::BORDER_REPLICATE);
  const int n = std::max(1, stripes);
  std::vector<std::vector<Extremum>> parts(n);
  const int span = rows - 2 * border;
  auto unique = [&](int x, int y, float v) {  // no other pixel of the window reaches v
    for (int dy = -r; dy <= r; ++dy) {
      const float* rr = kappa.ptr<float>(y + dy);
      for (int dx = -r; dx <= r; ++dx) {
        if ((dx | dy) != 0 && rr[x + dx] == v) return false;
      }
    }
    return true;
  };
  auto work = [&](int s) {
    std::vector<Extremum>& part = parts[s];
    part.clear();
    const int y0 = border + static_cast<int>(static_cast<long>(span) * s / n);
    const int y1 = border + static_cast<int>(static_cast<long>(span) * (s + 1) / n);
    for (int y = y0; y < y1; ++y) {
      const float* row = kappa.ptr<float>(y);
      const float* rmx = mx.ptr<float>(y);
      const float* rmn = mn.ptr<float>(y);
      const auto check = [&](int x) {
        const float k = row[x];
        if ((k >= threshold && k == rmx[x]) || (k <= -threshold && k == rmn[x])) {
          if (unique(x, y, k)) part.push_back({x, y, k});
        }
      };
      int x = border;
#if CV_SIMD
      // Most pixels are no candidate: skip a register of them at once (the same pixels, in order).
      const cv::v_float32 v_thr = cv::vx_setall_f32(threshold), v_neg_thr = cv::vx_setall_f32(-threshold);
      for (; x + cv::v_float32::nlanes <= cols - border; x += cv::v_float32::nlanes) {
        const cv::v_float32 k = cv::vx_load(row + x);
        const cv::v_float32 hit =
            ((k >= v_thr) & (k == cv::vx_load(rmx + x))) | ((k <= v_neg_thr) & (k == cv::vx_load(rmn + x)));
        if (!cv::v_check_any(hit)) continue;
        for (int i = 0; i < cv::v_float32::nlanes; ++i) check(x + i);
      }
#endif
      for (; x < cols - border; ++x) check(x);
    }
  };
  if (n == 1) {
    work(0);
  } else {
    cv::parallel_for_(
        cv::Range(0, n),
        [&](const cv::Range& rg) {
          for (int s = rg.start; s < rg.end; ++s) work(s);
        },
        n);
  }
  size_t total = 0;
  for (const auto& p : parts) total += p.size();
  out->reserve(total);
  for (const auto& p : parts) out->insert(out->end(), p.begin(), p.end());
}

bool hillClimb(const cv::Mat& kappa, const Eigen::Vector2f& prediction, const ClimbParams& p, Eigen::Vector2i* out) {
  const int xmin = p.border, ymin = p.border;
  const int xmax = kappa.cols - 1 - p.border, ymax = kappa.rows - 1 - p.border;
  // A prediction far outside any image (or not finite) has nothing to climb.
  if (!(std::fabs(prediction.x()) < 1e9f && std::fabs(prediction.y()) < 1e9f)) {
    *out = Eigen::Vector2i::Zero();
    return false;
  }
  int x = common::roundHalfAway(prediction.x());
  int y = common::roundHalfAway(prediction.y());
  *out = Eigen::Vector2i(x, y);
  if (x < xmin || x > xmax || y < ymin || y > ymax) return false;
  const float px = prediction.x(), py = prediction.y();
  auto F = [&](int xx, int yy) {
    const float dx = static_cast<float>(xx) - px, dy = static_cast<float>(yy) - py;
    const float d2 = dx * dx + dy * dy;
    return p.sign * kappa.ptr<float>(yy)[xx] + p.lambda * (p.sigma2 / (d2 + p.sigma2));
  };
  float best = F(x, y);
  for (int step = 0; step < p.max_steps; ++step) {
    int bx = x, by = y;
    float bv = best;
    for (int dy = -1; dy <= 1; ++dy) {
      const int yy = y + dy;
      if (yy < ymin || yy > ymax) continue;
      for (int dx = -1; dx <= 1; ++dx) {
        const int xx = x + dx;
        if ((dx | dy) == 0 || xx < xmin || xx > xmax) continue;
        const float v = F(xx, yy);
        if (v > bv) {
          bv = v;
          bx = xx;
          by = yy;
        }
      }
    }
    if (bx == x && by == y) {
      *out = Eigen::Vector2i(x, y);
      return true;
    }
    x = bx;
    y = by;
    best = bv;
  }
  *out = Eigen::Vector2i(x, y);
  return false;
}

Eigen::Vector2f refineSubpixel(const cv::Mat& kappa, const Eigen::Vector2i& p, float sign, float* peak) {
  const int x = p.x(), y = p.y();
  if (x < 1 || y < 1 || x >= kappa.cols - 1 || y >= kappa.rows - 1) {
    if (peak) *peak = x >= 0 && y >= 0 && x < kappa.cols && y < kappa.rows ? sign * kappa.ptr<float>(y)[x] : 0.f;
    return p.cast<float>();
  }
  const float* rm = kappa.ptr<float>(y - 1);
  const float* r0 = kappa.ptr<float>(y);
  const float* rp = kappa.ptr<float>(y + 1);
  const float c = sign * r0[x];
  const float l = sign * r0[x - 1], r = sign * r0[x + 1];
  const float u = sign * rm[x], d = sign * rp[x];
  const float gx = 0.5f * (r - l), gy = 0.5f * (d - u);
  const float hxx = l - 2.f * c + r, hyy = u - 2.f * c + d;
  const float hxy = 0.25f * sign * (rp[x + 1] - rp[x - 1] - rm[x + 1] + rm[x - 1]);
  float ox = 0.f, oy = 0.f;
  const float det = hxx * hyy - hxy * hxy;
  if (hxx < 0.f && det > 0.f) {
    // Full 2D quadratic (with the cross term): offset = -H^-1 g.
    ox = -(hyy * gx - hxy * gy) / det;
    oy = -(hxx * gy - hxy * gx) / det;
  } else {
    if (hxx < 0.f) ox = -gx / hxx;
    if (hyy < 0.f) oy = -gy / hyy;
  }
  ox = std::clamp(ox, -0.5f, 0.5f);
  oy = std::clamp(oy, -0.5f, 0.5f);
  if (peak) {
    const float q = c + gx * ox + gy * oy + 0.5f * (hxx * ox * ox + 2.f * hxy * ox * oy + hyy * oy * oy);
    *peak = std::max(c, q);  // never below the sample itself
  }
  return Eigen::Vector2f(static_cast<float>(x) + ox, static_cast<float>(y) + oy);
}

float peakSharpness(const cv::Mat& kappa, const Eigen::Vector2i& p, float sign) {
  const int x = p.x(), y = p.y();
  if (x < 1 || y < 1 || x >= kappa.cols - 1 || y >= kappa.rows - 1) return 0.f;
  const float* rm = kappa.ptr<float>(y - 1);
  const float* r0 = kappa.ptr<float>(y);
  const float* rp = kappa.ptr<float>(y + 1);
  const float c = sign * r0[x];
  if (!(c > 0.f)) return 0.f;
  const float hxx = sign * (r0[x - 1] + r0[x + 1]) - 2.f * c;
  const float hyy = sign * (rm[x] + rp[x]) - 2.f * c;
  const float hxy = 0.25f * sign * (rp[x + 1] - rp[x - 1] - rm[x + 1] + rm[x - 1]);
  // Larger eigenvalue of [hxx hxy; hxy hyy]: the flattest direction.
  const float half_tr = 0.5f * (hxx + hyy);
  const float disc = std::sqrt(0.25f * (hxx - hyy) * (hxx - hyy) + hxy * hxy);
  return -(half_tr + disc) / c;
}

float sampleBilinear(const cv::Mat& img, float x, float y) {
  x = std::clamp(x, 0.f, static_cast<float>(img.cols - 1));
  y = std::clamp(y, 0.f, static_cast<float>(img.rows - 1));
  const int x0 = std::min(static_cast<int>(x), img.cols - 2 < 0 ? 0 : img.cols - 2);
  const int y0 = std::min(static_cast<int>(y), img.rows - 2 < 0 ? 0 : img.rows - 2);
  const int x1 = std::min(x0 + 1, img.cols - 1), y1 = std::min(y0 + 1, img.rows - 1);
  const float ax = x - static_cast<float>(x0), ay = y - static_cast<float>(y0);
  const float* r0 = img.ptr<float>(y0);
  const float* r1 = img.ptr<float>(y1);
  return (1 - ay) * ((1 - ax) * r0[x0] + ax * r0[x1]) + ay * ((1 - ax) * r1[x0] + ax * r1[x1]);
}

}  // namespace vitamin_e::tracking
