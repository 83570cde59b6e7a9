// The dense tracker across a one-frame exposure step (an auto-exposure jump):
// the image brightness is scaled by 1.5 or 0.6 from one frame to the next while
// the sensor's read noise stays the same. kappa is cubic in intensity, so every
// curvature peak scales by ~g^3, while the frame's median |kappa| (the unit of
// the normalized curvature), which flat, noisy areas dominate, does not follow;
// an unmodelled contrast gain also biases the patch alignment. The tracks must
// survive the step and stay on the texture.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "vitamin_e/tracking/dense_tracker.h"
#include "vitamin_e/tracking/patch_align.h"

namespace vt = vitamin_e::tracking;

namespace {

struct Blob {
  double x, y, s, a;
};

// Overlapping Gaussian blobs on the left `fraction` of the image, flat grey
// background elsewhere: the flat part, where only the noise curves the image,
// sets the median |kappa|.
std::vector<Blob> texturedPart(int n, int w, int h, double fraction, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> ux(-10, fraction * w), uy(-10, h + 10), us(1.8, 4.0), ua(20, 45), sign(0, 1);
  std::vector<Blob> b(n);
  for (auto& bl : b) bl = {ux(rng), uy(rng), us(rng), sign(rng) < 0.5 ? -ua(rng) : ua(rng)};
  return b;
}

// Radiance of the texture shifted by t, in grey levels at gain 1 (background 90).
cv::Mat radiance(const std::vector<Blob>& blobs, int w, int h, const Eigen::Vector2d& t) {
  cv::Mat img(h, w, CV_32F);
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const double x = u - t.x(), y = v - t.y();
      double val = 90.0;
      for (const Blob& b : blobs) {
        const double dx = x - b.x, dy = y - b.y;
        const double d2 = dx * dx + dy * dy;
        if (d2 < 25.0 * b.s * b.s) val += b.a * std::exp(-d2 / (2 * b.s * b.s));
      }
      img.at<float>(v, u) = static_cast<float>(val);
    }
  }
  return img;
}

// The 8-bit image at exposure gain g: g * radiance plus read noise of 2 grey
// levels that does not scale with the exposure.
cv::Mat expose(const cv::Mat& rad, double g, unsigned seed) {
  cv::Mat noise(rad.size(), CV_32F), out;
  cv::theRNG().state = seed;
  cv::randn(noise, 0.0, 2.0);
  cv::Mat f = rad * g + noise;
  f.convertTo(out, CV_8U);
  return out;
}

struct StepResult {
  int before = 0;      // tracked points of the frame before the step (age >= 1)
  int continued = 0;   // of them tracked into the step frame
  int within_1px = 0;  // ... and within 1 px of the true position
  int next = 0;        // of those, tracked on into the frame after the step (same exposure)
};

// Frames 0..5 at gain 1, then frames 6 and 7 at gain `g`; the texture moves by
// `step` px per frame. Counts the tracks of frame 5 through the step to frame 6
// (or, g = 1, through an ordinary frame) and on to frame 7: a loss only put
// off by one frame would show there.
StepResult trackThroughStep(const vt::TrackerConfig& cfg, double g) {
  const int w = 320, h = 240;
  const auto blobs = texturedPart(400, w, h, 0.45, 21);
  const Eigen::Vector2d step(1.3, -0.8);
  vt::DenseTracker tracker(cfg);
  // Only tracks that already survived a step count: new extrema are
  // half-tested and end often in any frame.
  std::map<std::uint64_t, Eigen::Vector2f> tracked;
  StepResult r;
  std::map<std::uint64_t, Eigen::Vector2f> through;  // tracked from frame 5 into 6, within 1 px
  for (int k = 0; k <= 7; ++k) {
    const cv::Mat img = expose(radiance(blobs, w, h, step * k), k >= 6 ? g : 1.0, 100 + k);
    const vt::TrackerFrame f = tracker.track(img, 0.05 * k);
    if (k == 5) {
      for (const auto& p : f.points) {
        if (p.age > 0) tracked[p.id] = p.uv;
      }
      r.before = static_cast<int>(tracked.size());
    }
    if (k == 6) {
      for (const auto& p : f.points) {
        const auto it = tracked.find(p.id);
        if (p.age == 0 || it == tracked.end()) continue;
        ++r.continued;
        if ((p.uv - (it->second + step.cast<float>())).norm() <= 1.0f) {
          ++r.within_1px;
          through[p.id] = p.uv;
        }
      }
    }
    if (k == 7) {
      for (const auto& p : f.points) r.next += p.age > 0 && through.count(p.id) > 0;
    }
  }
  return r;
}

vt::TrackerConfig smallImageConfig() {
  vt::TrackerConfig cfg;
  cfg.brief_scale = 1.0 / 3.0;  // small synthetic image
  cfg.brief_patch_size = 11;
  cfg.threads = 1;
  return cfg;
}

void expectTracksSurvive(const vt::TrackerConfig& cfg, double g) {
  const StepResult r = trackThroughStep(cfg, g);
  ASSERT_GT(r.before, 150) << "too few tracks before the step for the test to mean anything";
  EXPECT_GE(r.continued, 0.8 * r.before) << "gain " << g << ": " << r.continued << " of " << r.before
                                         << " tracks continued";
  EXPECT_GE(r.within_1px, 0.8 * r.before)
      << "gain " << g << ": " << r.within_1px << " of " << r.before << " tracks continued within 1 px";
  EXPECT_GE(r.within_1px, 0.98 * r.continued) << "gain " << g;
  EXPECT_GE(r.next, 0.8 * r.within_1px) << "gain " << g << ": " << r.next << " of " << r.within_1px
                                        << " tracks went on into the frame after the step";
}

}  // namespace

// Without a step the same sequence keeps its tracks: the baseline the step is
// compared with.
TEST(TrackerExposure, TracksContinueWithoutStep) { expectTracksSurvive(smallImageConfig(), 1.0); }

TEST(TrackerExposure, TracksSurviveBrighteningStep) { expectTracksSurvive(smallImageConfig(), 1.5); }

TEST(TrackerExposure, TracksSurviveDarkeningStep) { expectTracksSurvive(smallImageConfig(), 0.6); }

// The SLAM's settings (config/euroc.yaml): no patch confirmation, strengths at
// the integer maximum, half-weight patch filter with a 7x7 patch.
TEST(TrackerExposure, TracksSurviveStepsWithSlamSettings) {
  vt::TrackerConfig cfg = smallImageConfig();
  cfg.lambda = 2.0;
  cfg.min_track_sharpness = 0.03;
  cfg.strength_at_subpixel_peak = false;
  cfg.max_align_disagreement_px = 0.0;
  cfg.extremum_weight = 0.5;
  cfg.align_radius_px = 3;
  expectTracksSurvive(cfg, 1.5);
  expectTracksSurvive(cfg, 0.6);
}

// The frame's strength change is measured (about g^3 over the median's change)
// and the old behaviour stays available.
TEST(TrackerExposure, ReportsTheFrameStrengthChange) {
  const int w = 320, h = 240;
  const auto blobs = texturedPart(400, w, h, 0.45, 21);
  vt::DenseTracker tracker(smallImageConfig());
  const auto rad = radiance(blobs, w, h, Eigen::Vector2d::Zero());
  const auto f0 = tracker.track(expose(rad, 1.0, 1), 0.0);
  const auto f1 = tracker.track(expose(rad, 1.0, 2), 0.05);
  EXPECT_NEAR(f1.strength_ratio, 1.0, 0.1);
  EXPECT_NEAR(f1.patch_gain, 1.0, 0.05);
  const auto f2 = tracker.track(expose(rad, 1.5, 3), 0.1);
  // Peaks scale by 1.5^3 = 3.4; the median |kappa| by less.
  EXPECT_GT(f2.curvature_scale, f1.curvature_scale);
  EXPECT_GT(f2.strength_ratio, 1.2);
  EXPECT_NEAR(f2.strength_ratio * f2.curvature_scale / f1.curvature_scale, 3.375, 0.5);
  EXPECT_NEAR(f2.patch_gain, 1.5, 0.1);
  vt::TrackerConfig off = smallImageConfig();
  off.relative_strength_change = false;
  off.align_gain = false;
  vt::DenseTracker plain(off);
  plain.track(expose(rad, 1.0, 1), 0.0);
  const auto g1 = plain.track(expose(rad, 1.5, 3), 0.05);
  EXPECT_EQ(g1.strength_ratio, 1.0);
  EXPECT_EQ(g1.patch_gain, 1.0);
  (void)f0;
}

// The gain-compensated patch alignment recovers a sub-pixel shift under a
// contrast gain of 1.5 and 0.6 plus an offset about as well as the mean-only
// alignment does without a gain; the mean-only one fails or is pulled off.
TEST(PatchAlign, GainCompensationRecoversShiftUnderContrastChange) {
  const int w = 120, h = 100;
  const auto blobs = texturedPart(200, w, h, 1.0, 5);
  const Eigen::Vector2d t(0.4, -0.3);
  const cv::Mat a = radiance(blobs, w, h, Eigen::Vector2d::Zero());
  const cv::Mat b0 = radiance(blobs, w, h, t);
  auto p90 = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() * 9 / 10];
  };
  for (double g : {1.5, 0.6}) {
    const cv::Mat b = b0 * g + 7.0;
    const vt::PatchAlignParams with{3, 2, 1.5f, true}, without{3, 2, 1.5f, false};
    std::vector<double> err_with, err_without, err_plain, gains;
    int tried = 0;
    for (int y = 15; y < h - 15; y += 6) {
      for (int x = 15; x < w - 15; x += 6) {
        ++tried;
        const Eigen::Vector2f p0(x, y);
        Eigen::Vector2f p = p0, q = p0, c = p0;
        float gain = 0.f;
        // Failures count as no correction (error = the shift itself).
        if (vt::alignPatch(a, b, p0, with, &p, &gain)) gains.push_back(gain);
        vt::alignPatch(a, b, p0, without, &q);
        vt::alignPatch(a, b0, p0, without, &c);  // reference: no gain, mean-only alignment
        const Eigen::Vector2f tf = t.cast<float>();
        err_with.push_back((p - p0 - tf).norm());
        err_without.push_back((q - p0 - tf).norm());
        err_plain.push_back((c - p0 - tf).norm());
      }
    }
    ASSERT_GT(tried, 100);
    ASSERT_GT(gains.size(), 0.9 * tried);
    std::sort(gains.begin(), gains.end());
    EXPECT_NEAR(gains[gains.size() / 2], g, 0.03 * g);
    EXPECT_LT(p90(err_with), 0.15) << "gain " << g;
    EXPECT_LT(p90(err_with), 1.5 * p90(err_plain) + 0.01) << "gain " << g;
    EXPECT_GT(p90(err_without), 0.3) << "gain " << g;
  }
}

TEST(TrackerConfig, ValidateNamesTheExposureFields) {
  for (const char* field : {"strength_ratio_min_change", "align_gain_min_change"}) {
    vt::TrackerConfig c;
    EXPECT_NO_THROW(c.validate());
    (std::string(field) == "align_gain_min_change" ? c.align_gain_min_change : c.strength_ratio_min_change) = -0.1;
    try {
      c.validate();
      ADD_FAILURE() << field << ": expected invalid_argument";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
  }
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
