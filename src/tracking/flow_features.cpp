#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>

#include "tracker_internal.h"
#include "vitamin_e/tracking/curvature.h"

namespace vitamin_e::tracking {

void extractSmallFeatures(const cv::Mat& gray, const TrackerConfig& cfg, const BriefExtractor& brief,
                          SmallFeatures* out) {
  out->pos.clear();
  out->desc.clear();
  out->sign.clear();
  const int sw = std::max(1, static_cast<int>(std::lround(gray.cols * cfg.brief_scale)));
  const int sh = std::max(1, static_cast<int>(std::lround(gray.rows * cfg.brief_scale)));
  const int r = brief.radius();
  if (sw <= 2 * r + 4 || sh <= 2 * r + 4) return;
  cv::Mat small, ks, smoothed;
  cv::resize(gray, small, cv::Size(sw, sh), 0, 0, cv::INTER_AREA);
  computeCurvature(small, 1.0, &ks, 1, &smoothed);
  const float scale = robustCurvatureScale(ks, 1);
  if (scale <= 0.f) return;
  std::vector<Extremum> ex;
  detectExtrema(ks, 1, std::max(scale * static_cast<float>(cfg.min_curvature), 1e-6f), r + 1, &ex, 1);
  if (static_cast<int>(ex.size()) > cfg.brief_max_keypoints) {
    std::nth_element(ex.begin(), ex.begin() + cfg.brief_max_keypoints, ex.end(),
                     [](const Extremum& a, const Extremum& b) { return std::fabs(a.kappa) > std::fabs(b.kappa); });
    ex.resize(cfg.brief_max_keypoints);
  }
  const double fx = static_cast<double>(gray.cols) / sw, fy = static_cast<double>(gray.rows) / sh;
  for (const Extremum& e : ex) {
    BriefDescriptor d;
    if (!brief.describe(smoothed, e.x, e.y, &d)) continue;
    const float s = e.kappa > 0.f ? 1.f : -1.f;
    const Eigen::Vector2f p = refineSubpixel(ks, Eigen::Vector2i(e.x, e.y), s);
    out->pos.emplace_back((p.x() + 0.5) * fx - 0.5, (p.y() + 0.5) * fy - 0.5);
    out->desc.push_back(d);
    out->sign.push_back(static_cast<signed char>(s));
  }
}

// Noise sigma (Immerkaer 1996: mean |I * [1 -2 1; -2 4 -2; 1 -2 1]| * sqrt(pi/2) / 6)
// over the median raw gradient magnitude, on a sparse set of rows.
double noiseToGradientRatio(const cv::Mat& g, std::vector<float>* grad) {
  grad->clear();
  double sum = 0.0;
  long n = 0;
  for (int y = 1; y + 1 < g.rows; y += 4) {
    const std::uint8_t* a = g.ptr<std::uint8_t>(y - 1);
    const std::uint8_t* b = g.ptr<std::uint8_t>(y);
    const std::uint8_t* c = g.ptr<std::uint8_t>(y + 1);
    for (int x = 1; x + 1 < g.cols; x += 2) {
      const int lap =
          (a[x - 1] - 2 * a[x] + a[x + 1]) - 2 * (b[x - 1] - 2 * b[x] + b[x + 1]) + (c[x - 1] - 2 * c[x] + c[x + 1]);
      sum += std::abs(lap);
      ++n;
      const float gx = 0.5f * static_cast<float>(b[x + 1] - b[x - 1]), gy = 0.5f * static_cast<float>(c[x] - a[x]);
      grad->push_back(std::sqrt(gx * gx + gy * gy));
    }
  }
  if (n == 0) return 0.0;
  const double noise = std::sqrt(M_PI / 2.0) / 6.0 * sum / static_cast<double>(n);
  auto mid = grad->begin() + static_cast<long>(grad->size() / 2);
  std::nth_element(grad->begin(), mid, grad->end());
  return *mid > 1e-6f ? noise / *mid : 0.0;
}


}  // namespace vitamin_e::tracking
