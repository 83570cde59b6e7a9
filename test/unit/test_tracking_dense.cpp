// Unit tests of the dense curvature-extrema tracker on synthetic images made here.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <climits>
#include <cmath>
#include <map>
#include <random>
#include <set>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "vitamin_e/tracking/affine_flow.h"
#include "vitamin_e/tracking/brief.h"
#include "vitamin_e/tracking/curvature.h"
#include "vitamin_e/tracking/dense_tracker.h"
#include "vitamin_e/tracking/patch_align.h"

namespace vt = vitamin_e::tracking;

namespace {

struct Blob {
  double x, y, s, a;
};

// Analytic texture: sum of Gaussian blobs on a grey background, evaluated at
// the warped position W^-1(u, v) so that warps are exact.
std::vector<Blob> randomBlobs(int n, int w, int h, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> ux(-20, w + 20), uy(-20, h + 20), us(1.8, 4.0), ua(-70, 70);
  std::vector<Blob> b(n);
  for (auto& bl : b) bl = {ux(rng), uy(rng), us(rng), ua(rng)};
  return b;
}

cv::Mat renderBlobs(const std::vector<Blob>& blobs, int w, int h, const Eigen::Matrix2d& A, const Eigen::Vector2d& t) {
  // Image(u) = texture(A^-1 (u - t)).
  const Eigen::Matrix2d Ai = A.inverse();
  cv::Mat img(h, w, CV_8UC1);
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const Eigen::Vector2d p = Ai * (Eigen::Vector2d(u, v) - t);
      double val = 128.0;
      for (const Blob& b : blobs) {
        const double dx = p.x() - b.x, dy = p.y() - b.y;
        const double d2 = dx * dx + dy * dy;
        if (d2 < 25.0 * b.s * b.s) val += b.a * std::exp(-d2 / (2 * b.s * b.s));
      }
      img.at<std::uint8_t>(v, u) = cv::saturate_cast<std::uint8_t>(val);
    }
  }
  return img;
}

// 600 far blobs over the image and `near_count` near ones right of column `split`, each layer
// moved by its own translation (near and far structure under a sideways camera motion): the
// images before and after the motion.
std::pair<cv::Mat, cv::Mat> twoLayerImages(int w, int h, int split, unsigned seed, int near_count,
                                           const Eigen::Vector2d& t_far, const Eigen::Vector2d& t_near) {
  const auto far = randomBlobs(600, w, h, seed), near = randomBlobs(near_count, w, h, seed + 1);
  const auto render = [&](const Eigen::Vector2d& tf, const Eigen::Vector2d& tn) {
    cv::Mat img = renderBlobs(far, w, h, Eigen::Matrix2d::Identity(), tf);
    renderBlobs(near, w, h, Eigen::Matrix2d::Identity(), tn).colRange(split, w).copyTo(img.colRange(split, w));
    return img;
  };
  return {render(Eigen::Vector2d::Zero(), Eigen::Vector2d::Zero()), render(t_far, t_near)};
}

// The tracker of the two-layer tests: BRIEF on a third of these small images.
vt::TrackerConfig twoLayerConfig(bool retry_from_prior) {
  vt::TrackerConfig cfg;
  cfg.brief_scale = 1.0 / 3.0;
  cfg.brief_patch_size = 11;
  cfg.retry_from_prior = retry_from_prior;
  return cfg;
}

// The tracks of the frame before found within 1 px of where they went (truth: by track id).
int foundWhereTheyWent(const std::vector<vt::TrackedPoint>& points,
                       const std::map<std::uint64_t, Eigen::Vector2f>& truth) {
  int right = 0;
  for (const auto& p : points) {
    const auto it = truth.find(p.id);
    if (p.age > 0 && it != truth.end() && (p.uv - it->second).norm() <= 1.0f) ++right;
  }
  return right;
}

Eigen::Matrix2d rotation(double deg) {
  const double a = deg * M_PI / 180.0;
  Eigen::Matrix2d R;
  R << std::cos(a), -std::sin(a), std::sin(a), std::cos(a);
  return R;
}

// The image with Gaussian noise of sigma 8 grey levels (OpenCV's RNG seeded with seed).
cv::Mat withNoise(const cv::Mat& img, unsigned seed) {
  cv::Mat f, noise(img.size(), CV_32F);
  cv::theRNG().state = seed;
  cv::randn(noise, 0.0, 8.0);
  img.convertTo(f, CV_32F);
  f += noise;
  f.convertTo(f, CV_8U);
  return f;
}

}  // namespace

// detectExtrema against the definition, pixel by pixel: strict window maxima of kappa and of
// -kappa at or beyond the threshold, row-major. Values quantized to a few levels make ties
// (plateaus, which are no extremum); odd widths and borders leave a tail after the vector steps.
TEST(Curvature, ExtremaAreTheStrictWindowMaximaInRowMajorOrder) {
  cv::RNG rng(7);
  for (const cv::Size size : {cv::Size(37, 23), cv::Size(64, 48), cv::Size(131, 17)}) {
    for (const int levels : {5, 1000}) {
      cv::Mat kappa(size, CV_32FC1);
      for (int y = 0; y < size.height; ++y) {
        for (int x = 0; x < size.width; ++x) {
          kappa.at<float>(y, x) = static_cast<float>(rng.uniform(-levels, levels + 1)) / static_cast<float>(levels);
        }
      }
      for (const int r : {1, 2}) {
        for (const int border : {0, 3, 5}) {
          const float threshold = 0.3f;
          std::vector<vt::Extremum> got;
          vt::detectExtrema(kappa, r, threshold, border, &got);
          std::vector<vt::Extremum> want;
          const int b = std::max(border, r + 1);
          for (int y = b; y < size.height - b; ++y) {
            for (int x = b; x < size.width - b; ++x) {
              const float k = kappa.at<float>(y, x);
              if (std::fabs(k) < threshold) continue;
              bool strict = true;
              for (int dy = -r; dy <= r && strict; ++dy) {
                for (int dx = -r; dx <= r && strict; ++dx) {
                  if (dx == 0 && dy == 0) continue;
                  const float v = kappa.at<float>(y + dy, x + dx);
                  strict = k > 0.f ? v < k : v > k;
                }
              }
              if (strict) want.push_back({x, y, k});
            }
          }
          ASSERT_EQ(got.size(), want.size()) << size << " levels " << levels << " r " << r << " border " << border;
          for (std::size_t i = 0; i < want.size(); ++i) {
            EXPECT_EQ(got[i].x, want[i].x);
            EXPECT_EQ(got[i].y, want[i].y);
            EXPECT_EQ(got[i].kappa, want[i].kappa);
          }
        }
      }
    }
  }
}

// kappa = f'(r)^3 / r for a radial profile: for a bright Gaussian blob it is
// zero at the centre and most negative on the ring r = s*sqrt(2/3) (s includes
// the pre-smoothing). The extrema must lie on that ring, centred on the blob.
TEST(Curvature, GaussianBlobExtremaCentredOnBlob) {
  const int w = 64, h = 64;
  const double cx = 31.6, cy = 32.3, s = 4.0;
  cv::Mat img(h, w, CV_32FC1);
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u)
      img.at<float>(v, u) =
          static_cast<float>(20.0 + 200.0 * std::exp(-((u - cx) * (u - cx) + (v - cy) * (v - cy)) / (2 * s * s)));
  cv::Mat kappa;
  vt::computeCurvature(img, 1.0, &kappa);
  std::vector<vt::Extremum> ex;
  vt::detectExtrema(kappa, 2, 1e-3f * static_cast<float>(cv::norm(kappa, cv::NORM_INF)), 3, &ex);
  ASSERT_GE(ex.size(), 3u);
  const double ring = std::sqrt(s * s + 1.0) * std::sqrt(2.0 / 3.0);
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  int n = 0;
  float kmin = 0.f;
  for (const auto& e : ex) {
    if (e.kappa >= 0.f) continue;  // a bright blob: minima of kappa (maxima of -kappa)
    const Eigen::Vector2f p = vt::refineSubpixel(kappa, {e.x, e.y}, -1.f);
    const double r = std::hypot(p.x() - cx, p.y() - cy);
    EXPECT_NEAR(r, ring, 0.6) << "extremum at " << p.transpose();
    mean += p.cast<double>();
    ++n;
    kmin = std::min(kmin, e.kappa);
  }
  ASSERT_GE(n, 3);
  mean /= n;
  EXPECT_LT((mean - Eigen::Vector2d(cx, cy)).norm(), 0.5);
  // The centre itself is a (near) zero of kappa.
  const float kc = vt::sampleBilinear(kappa, static_cast<float>(cx), static_cast<float>(cy));
  EXPECT_LT(std::fabs(kc), 0.25f * std::fabs(kmin));
}

TEST(AffineFlow, RecoversKnownAffineWithHalfOutliers) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> ux(0, 752), uy(0, 480);
  std::normal_distribution<double> noise(0.0, 0.4);
  Eigen::Matrix2d A;
  A << 1.02, -0.03, 0.04, 0.985;
  const Eigen::Vector2d b(12.0, -7.5);
  std::vector<Eigen::Vector2d> x, y;
  for (int i = 0; i < 200; ++i) {
    const Eigen::Vector2d p(ux(rng), uy(rng));
    x.push_back(p);
    if (i % 2 == 0) {
      y.push_back(A * p + b + Eigen::Vector2d(noise(rng), noise(rng)));
    } else {
      y.emplace_back(ux(rng), uy(rng));  // outlier anywhere in the image
    }
  }
  vt::AffineFitConfig cfg;
  const vt::AffineFit fit = vt::fitAffineGemanMcClure(x, y, cfg);
  ASSERT_TRUE(fit.ok);
  EXPECT_LT((fit.A - A).cwiseAbs().maxCoeff(), 0.004);
  EXPECT_LT((fit.b - b).norm(), 1.0);
  EXPECT_GE(fit.inliers, 95);
  EXPECT_LE(fit.inliers, 110);
  // Plain least squares would be far off: make sure the data really is hard.
  Eigen::MatrixXd H(x.size(), 3), Y(x.size(), 2);
  for (size_t i = 0; i < x.size(); ++i) {
    H.row(static_cast<Eigen::Index>(i)) << x[i].x(), x[i].y(), 1.0;
    Y.row(static_cast<Eigen::Index>(i)) = y[i].transpose();
  }
  const Eigen::MatrixXd P = H.colPivHouseholderQr().solve(Y);
  EXPECT_GT((P.row(2).transpose() - b).norm(), 5.0);
}

TEST(HillClimb, FollowsTranslatedRotatedPattern) {
  const int w = 200, h = 160;
  const auto blobs = randomBlobs(260, w, h, 3);
  const Eigen::Matrix2d R = rotation(1.5);
  const Eigen::Vector2d c(100, 80), t(2.6, -1.7);
  const Eigen::Vector2d tt = c + t - R * c;  // y = R (x - c) + c + t
  const cv::Mat img0 = renderBlobs(blobs, w, h, Eigen::Matrix2d::Identity(), Eigen::Vector2d::Zero());
  const cv::Mat img1 = renderBlobs(blobs, w, h, R, tt);
  const vt::TrackerConfig cfg;  // the tracker's defaults
  cv::Mat k0, k1;
  vt::computeCurvature(img0, cfg.smoothing_sigma, &k0);
  vt::computeCurvature(img1, cfg.smoothing_sigma, &k1);
  const float scale = vt::robustCurvatureScale(k0);
  std::vector<vt::Extremum> ex;
  vt::detectExtrema(k0, 2, 3.f * scale, 12, &ex);
  ASSERT_GT(ex.size(), 50u);
  std::vector<double> err;
  for (const auto& e : ex) {
    const float sgn = e.kappa > 0 ? 1.f : -1.f;
    const Eigen::Vector2f p0 = vt::refineSubpixel(k0, {e.x, e.y}, sgn);
    const Eigen::Vector2d truth = R * p0.cast<double>() + tt;
    // Prediction off by up to a pixel (a coarse dominant flow).
    const Eigen::Vector2f pred = (truth + Eigen::Vector2d(0.7, -0.6)).cast<float>();
    vt::ClimbParams cp{sgn, static_cast<float>(cfg.lambda) * scale,
                       static_cast<float>(cfg.track_sigma_px * cfg.track_sigma_px), cfg.max_climb_steps, 2};
    Eigen::Vector2i q;
    if (!vt::hillClimb(k1, pred, cp, &q)) continue;
    // Polish on kappa alone (TrackerConfig::polish_steps): with a prediction
    // deliberately off by ~1 px the prior biases F's maximum.
    const vt::ClimbParams pol{sgn, 0.f, 1.f, 2, 2};
    if (!vt::hillClimb(k1, q.cast<float>(), pol, &q)) continue;
    err.push_back((vt::refineSubpixel(k1, q, sgn).cast<double>() - truth).norm());
  }
  ASSERT_GT(err.size(), 0.9 * ex.size());
  std::sort(err.begin(), err.end());
  EXPECT_LT(err[err.size() / 2], 0.2) << "median error";
  EXPECT_LT(err[err.size() * 8 / 10], 0.35) << "80th percentile";
}

TEST(DenseTracker, TracksWarpedPatternEndToEnd) {
  const int w = 320, h = 240;
  const auto blobs = randomBlobs(700, w, h, 11);
  const Eigen::Matrix2d R = rotation(1.0);
  const Eigen::Vector2d c(160, 120), t(-4.3, 3.2);
  const Eigen::Vector2d tt = c + t - R * c;
  vt::TrackerConfig cfg;
  cfg.brief_scale = 1.0 / 3.0;  // small synthetic image
  cfg.brief_patch_size = 11;
  vt::DenseTracker tracker(cfg);
  const auto f0 = tracker.track(renderBlobs(blobs, w, h, Eigen::Matrix2d::Identity(), Eigen::Vector2d::Zero()), 0.0);
  ASSERT_GT(f0.points.size(), 200u);
  EXPECT_EQ(f0.num_new, static_cast<int>(f0.points.size()));
  const auto f1 = tracker.track(renderBlobs(blobs, w, h, R, tt), 0.05);
  EXPECT_TRUE(f1.flow_ok);
  EXPECT_LT((f1.b - tt).norm(), 3.0);
  std::map<std::uint64_t, Eigen::Vector2f> before;
  for (const auto& p : f0.points) before[p.id] = p.uv;
  std::vector<double> err;
  for (const auto& p : f1.points) {
    if (p.age == 0) continue;
    EXPECT_EQ(p.age, 1);
    ASSERT_TRUE(before.count(p.id));
    err.push_back((p.uv.cast<double>() - (R * before[p.id].cast<double>() + tt)).norm());
  }
  // The sharpness check drops many of the ring-shaped extrema around isolated
  // blobs (they slide along the ring): about two thirds survive here.
  ASSERT_GT(err.size(), 0.6 * f0.points.size());
  EXPECT_EQ(f1.num_tracked, static_cast<int>(err.size()));
  std::sort(err.begin(), err.end());
  EXPECT_LT(err[err.size() / 2], 0.2);
  EXPECT_GT(std::count_if(err.begin(), err.end(), [](double e) { return e < 1.0; }), 0.95 * err.size());
  // Dropped tracks disappear.
  std::vector<std::uint64_t> drop{f1.points[0].id, f1.points[1].id};
  // Repeated and unknown ids do not count.
  EXPECT_EQ(tracker.dropTracks({drop[0], drop[1], drop[0], 0xFFFFFFFFFFull}), 2u);
  EXPECT_EQ(tracker.dropTracks(drop), 0u);
  const auto f2 = tracker.track(renderBlobs(blobs, w, h, R, tt), 0.1);
  for (const auto& p : f2.points) EXPECT_TRUE(p.id != drop[0] && p.id != drop[1]);
}

// Two layers that move differently (a near hedge and far houses after dropped
// frames): the dominant flow follows the larger one and loses the tracks of
// the other; where the caller knows where each track should be (its map point
// seen from the predicted pose), those are tracked again from there. The
// priors share a common error (the motion model's), which the BRIEF matches
// around the mapped tracks correct.
// A caller that must wait for its priors (the pipelined system, for the pose of the frame
// before) is asked for them once per frame, after the flow's pass, and only when the retry is
// on; what it gives is used as the same priors given up front are.
TEST(DenseTracker, PriorsAreAskedForOncePerFrameAndOnlyWhenUsed) {
  const int w = 360, h = 240, split = 240;
  const Eigen::Vector2d t_far(3.0, 1.0), t_near(21.0, 2.0);
  const std::pair<cv::Mat, cv::Mat> images = twoLayerImages(w, h, split, 21, 300, t_far, t_near);
  const auto run = [&](bool retry, bool provider, int* calls) {
    vt::DenseTracker tracker(twoLayerConfig(retry));
    const auto f0 = tracker.track(images.first, 0.0, vt::DenseTracker::PriorProvider([calls] {
                                    ++*calls;
                                    return std::vector<vt::TrackPrior>{};
                                  }));
    std::vector<vt::TrackPrior> priors;
    for (const auto& p : f0.points) {
      if (p.uv.x() > split + 10) priors.push_back({p.id, p.uv + t_near.cast<float>()});
    }
    if (!provider) return tracker.track(images.second, 0.05, priors);
    return tracker.track(images.second, 0.05, vt::DenseTracker::PriorProvider([&priors, calls] {
                           ++*calls;
                           return priors;
                         }));
  };
  int calls = 0;
  const auto given = run(true, false, &calls);
  EXPECT_EQ(calls, 0) << "the first frame has nothing to retry";
  const auto asked = run(true, true, &calls);
  EXPECT_EQ(calls, 1);
  ASSERT_GT(given.num_from_prior, 40);
  EXPECT_EQ(asked.num_from_prior, given.num_from_prior);
  ASSERT_EQ(asked.points.size(), given.points.size());
  for (std::size_t i = 0; i < asked.points.size(); ++i) EXPECT_EQ(asked.points[i].uv, given.points[i].uv);
  calls = 0;
  run(false, true, &calls);
  EXPECT_EQ(calls, 0) << "the retry is off: no caller waits for priors";
}

TEST(DenseTracker, PriorsRecoverTheTracksOfASecondLayer) {
  const int w = 360, h = 240, split = 240;
  const Eigen::Vector2d t_far(3.0, 1.0), t_near(21.0, 2.0);
  const std::pair<cv::Mat, cv::Mat> images = twoLayerImages(w, h, split, 21, 300, t_far, t_near);
  const cv::Mat &img0 = images.first, &img1 = images.second;
  const Eigen::Vector2f prior_error(2.0f, -1.5f);
  struct Outcome {
    int far_right = 0, far_total = 0, near_right = 0, near_total = 0, from_prior = 0;
  };
  const auto run = [&](bool retry, bool with_priors) {
    vt::DenseTracker tracker(twoLayerConfig(retry));
    const auto f0 = tracker.track(img0, 0.0);
    std::vector<vt::TrackPrior> priors;
    std::map<std::uint64_t, Eigen::Vector2f> truth;
    for (const auto& p : f0.points) {
      // Tracks well inside one layer, before and after the motion.
      const bool near = p.uv.x() > split + 10;
      if (!near && p.uv.x() > split - 30) continue;
      const Eigen::Vector2f to = p.uv + (near ? t_near : t_far).cast<float>();
      if (to.x() > w - 12 || to.y() > h - 12) continue;
      truth[p.id] = to;
      priors.push_back({p.id, to + prior_error});
    }
    const auto f1 = tracker.track(img1, 0.05, with_priors ? priors : std::vector<vt::TrackPrior>{});
    Outcome o;
    o.from_prior = f1.num_from_prior;
    for (const auto& [id, to] : truth) (to.x() > split + 10 + t_near.x() ? o.near_total : o.far_total) += 1;
    for (const auto& p : f1.points) {
      const auto it = truth.find(p.id);
      if (p.age == 0 || it == truth.end() || (p.uv - it->second).norm() > 1.0f) continue;
      (it->second.x() > split + 10 + t_near.x() ? o.near_right : o.far_right) += 1;
    }
    return o;
  };
  const Outcome flow_only = run(false, true);  // priors given but the retry is off
  const Outcome no_priors = run(true, false);  // the retry is on but nothing is known
  const Outcome with_priors = run(true, true);
  ASSERT_GT(flow_only.near_total, 40);
  ASSERT_GT(flow_only.far_right, 150);
  // The flow follows the far layer and loses the near one.
  EXPECT_LT(flow_only.near_right, 0.2 * flow_only.near_total);
  EXPECT_EQ(no_priors.near_right, flow_only.near_right);
  EXPECT_EQ(no_priors.far_right, flow_only.far_right);
  // From the priors, the near tracks are found where they went nearly as often as
  // the far ones (three quarters as often here: the sharpness check ends many ring extrema of
  // isolated blobs in either layer); the far ones stay.
  const double far_share = static_cast<double>(flow_only.far_right) / flow_only.far_total;
  EXPECT_GT(with_priors.near_right, 0.5 * far_share * with_priors.near_total);
  EXPECT_GE(with_priors.far_right, flow_only.far_right);
  EXPECT_EQ(flow_only.from_prior, 0);
  EXPECT_GE(with_priors.from_prior, with_priors.near_right);
}

// Only the near layer is mapped (the far one is too far for parallax) and the motion model is
// off by 9 px (a turn that starts): no map track the flow kept can tell the priors' error, the
// BRIEF matches around the mapped tracks do, and the near tracks are found from the priors
// corrected by them nearly as often as from exact priors.
TEST(DenseTracker, PriorsAreCorrectedByTheMatchesAroundTheirTracks) {
  const int w = 360, h = 240, split = 240;
  const Eigen::Vector2d t_far(3.0, 1.0), t_near(21.0, 2.0);
  const std::pair<cv::Mat, cv::Mat> images = twoLayerImages(w, h, split, 31, 500, t_far, t_near);
  const cv::Mat &img0 = images.first, &img1 = images.second;
  const auto near_found = [&](const Eigen::Vector2f& prior_error, int* total) {
    vt::DenseTracker tracker(twoLayerConfig(true));
    const auto f0 = tracker.track(img0, 0.0);
    std::vector<vt::TrackPrior> priors;
    std::map<std::uint64_t, Eigen::Vector2f> truth;
    for (const auto& p : f0.points) {
      if (p.uv.x() < split + 10) continue;  // the far layer has no map points
      const Eigen::Vector2f to = p.uv + t_near.cast<float>();
      if (to.x() > w - 12 || to.y() > h - 12) continue;
      truth[p.id] = to;
      priors.push_back({p.id, to + prior_error});
    }
    const auto f1 = tracker.track(img1, 0.05, priors);
    *total = static_cast<int>(truth.size());
    return foundWhereTheyWent(f1.points, truth);
  };
  int total = 0;
  const int exact = near_found(Eigen::Vector2f::Zero(), &total);
  ASSERT_GT(total, 40);
  ASSERT_GT(exact, 0.3 * total);
  const int off = near_found(Eigen::Vector2f(9.0f, -6.0f), &total);
  EXPECT_GT(off, 0.8 * exact) << "exact " << exact << " off " << off << " of " << total;
}

// The camera nears a near layer by a large step (dropped frames on a car): right of `split` the
// image grows by 1.4x, and with it every blob, whose curvature peak changes by more than the
// strength check allows; the far layer, most of the image, stays (so the frame's common change
// does not follow the near one). Priors at the right places that say the size change keep the
// near tracks the check ends otherwise; priors without it (scale 1) do not.
TEST(DenseTracker, APriorsSizeChangeWidensTheStrengthCheck) {
  const int w = 360, h = 240, split = 200;
  const double zoom = 1.4;
  const auto far = randomBlobs(600, w, h, 41), near = randomBlobs(300, w, h, 42);
  const Eigen::Vector2d centre(split + 20.0, h / 2.0);
  const Eigen::Matrix2d A = zoom * Eigen::Matrix2d::Identity();
  const Eigen::Vector2d t = centre - A * centre;
  const auto render = [&](const Eigen::Matrix2d& An, const Eigen::Vector2d& tn) {
    cv::Mat img = renderBlobs(far, w, h, Eigen::Matrix2d::Identity(), Eigen::Vector2d::Zero());
    renderBlobs(near, w, h, An, tn).colRange(split, w).copyTo(img.colRange(split, w));
    return img;
  };
  const cv::Mat img0 = render(Eigen::Matrix2d::Identity(), Eigen::Vector2d::Zero()), img1 = render(A, t);
  const auto found = [&](bool follow, float prior_scale, int* total) {
    vt::TrackerConfig cfg = twoLayerConfig(true);
    cfg.strength_follows_prior_scale = follow;
    cfg.min_track_sharpness = 0.0;  // a grown blob is flatter too: that check is not the one under test
    vt::DenseTracker tracker(cfg);
    const auto f0 = tracker.track(img0, 0.0);
    std::vector<vt::TrackPrior> priors;
    std::map<std::uint64_t, Eigen::Vector2f> truth;
    for (const auto& p : f0.points) {
      if (p.uv.x() < split + 10) continue;  // only the near layer is mapped
      const Eigen::Vector2f to = (A * p.uv.cast<double>() + t).cast<float>();
      if (to.x() < split + 10 || to.y() < 12 || to.x() > w - 12 || to.y() > h - 12) continue;
      truth[p.id] = to;
      priors.push_back({p.id, to, prior_scale});
    }
    const auto f1 = tracker.track(img1, 0.05, priors);
    *total = static_cast<int>(truth.size());
    return foundWhereTheyWent(f1.points, truth);
  };
  int total = 0;
  const int unknown = found(true, 1.f, &total);
  ASSERT_GT(total, 40);
  const int told = found(true, static_cast<float>(zoom), &total);
  const int off = found(false, static_cast<float>(zoom), &total);
  EXPECT_EQ(off, unknown);
  EXPECT_GT(told, unknown + 0.2 * total) << "scale 1: " << unknown << ", scale " << zoom << ": " << told << " of "
                                         << total;
}

// Every ended track is listed once with the check that ended it, in agreement
// with lost_by, and none of them is among the live points.
TEST(DenseTracker, EndedTracksNameTheirReason) {
  const int w = 320, h = 240;
  const auto blobs = randomBlobs(700, w, h, 5);
  vt::TrackerConfig cfg;
  cfg.brief_scale = 1.0 / 3.0;
  cfg.brief_patch_size = 11;
  vt::DenseTracker tracker(cfg);
  const auto f0 = tracker.track(renderBlobs(blobs, w, h, Eigen::Matrix2d::Identity(), Eigen::Vector2d::Zero()), 0.0);
  EXPECT_TRUE(f0.ended.empty());
  const auto f1 = tracker.track(withNoise(renderBlobs(blobs, w, h, rotation(2.0), Eigen::Vector2d(5, -3)), 3), 0.05);
  ASSERT_GT(f1.num_lost, 0);
  EXPECT_EQ(static_cast<int>(f1.ended.size()), f1.num_lost);
  std::map<std::string, int> by;
  std::set<std::uint64_t> ended, before, live;
  for (const auto& p : f0.points) before.insert(p.id);
  for (const auto& p : f1.points) live.insert(p.id);
  for (const auto& e : f1.ended) {
    ++by[e.second];
    EXPECT_TRUE(ended.insert(e.first).second) << "track " << e.first << " listed twice";
    EXPECT_TRUE(before.count(e.first));
    EXPECT_FALSE(live.count(e.first));
  }
  EXPECT_EQ(by, f1.lost_by);
}

// peakSharpness = -(flatter Hessian eigenvalue) / peak. For a round Gaussian
// peak of scale s the discrete value is 2(1 - exp(-1/(2 s^2))) ~ 1/s^2; a ridge
// (flat along y) scores 0 and a saddle scores < 0, whatever the sign convention.
TEST(Curvature, PeakSharpnessSeparatesPeaksFromRidgesAndSaddles) {
  const int n = 21, c = 10;
  const double s = 2.0;
  cv::Mat round(n, n, CV_32F), ridge(n, n, CV_32F), saddle(n, n, CV_32F), elong(n, n, CV_32F);
  for (int y = 0; y < n; ++y) {
    for (int x = 0; x < n; ++x) {
      const double dx = x - c, dy = y - c;
      round.at<float>(y, x) = static_cast<float>(-50.0 * std::exp(-(dx * dx + dy * dy) / (2 * s * s)));
      ridge.at<float>(y, x) = static_cast<float>(50.0 * std::exp(-dx * dx / (2 * s * s)));
      saddle.at<float>(y, x) = static_cast<float>(50.0 + dy * dy - dx * dx);
      elong.at<float>(y, x) = static_cast<float>(50.0 * std::exp(-dx * dx / (2 * s * s) - dy * dy / (2 * 16 * s * s)));
    }
  }
  const Eigen::Vector2i p(c, c);
  const double expect = 2.0 * (1.0 - std::exp(-1.0 / (2 * s * s)));
  EXPECT_NEAR(vt::peakSharpness(round, p, -1.f), expect, 1e-3);  // a minimum of kappa climbed as -kappa
  EXPECT_EQ(vt::peakSharpness(round, p, 1.f), 0.f);              // wrong sign: not a peak
  EXPECT_NEAR(vt::peakSharpness(ridge, p, 1.f), 0.0, 1e-6);
  EXPECT_LT(vt::peakSharpness(saddle, p, 1.f), 0.f);
  const float e = vt::peakSharpness(elong, p, 1.f);  // 4x longer along y: 16x flatter
  EXPECT_GT(e, 0.f);
  EXPECT_LT(e, 0.1 * expect);
  EXPECT_EQ(vt::peakSharpness(round, Eigen::Vector2i(0, 5), -1.f), 0.f);  // border
}

// The patch alignment recovers a sub-pixel translation to a few hundredths of
// a pixel, also under a brightness offset; flat patches and patches leaving
// the image fail.
// The height of a kappa peak read between pixels: the sample at the integer
// maximum under-reads a sharp peak that falls half a pixel away; the value of
// the fitted quadratic must not (the tracker compares peak heights frame to frame).
TEST(Curvature, SubpixelPeakHeightIndependentOfPhase) {
  cv::Mat k(21, 21, CV_32FC1);
  const double s = 1.2, height = 10.0;
  for (double ox : {0.0, 0.3, 0.45}) {
    for (int y = 0; y < k.rows; ++y) {
      for (int x = 0; x < k.cols; ++x) {
        const double dx = x - (10.0 + ox), dy = y - (10.0 - 0.5 * ox);
        k.at<float>(y, x) = static_cast<float>(-height * std::exp(-(dx * dx + dy * dy) / (2 * s * s)));
      }
    }
    float peak = 0.f;
    const Eigen::Vector2f p = vt::refineSubpixel(k, Eigen::Vector2i(10, 10), -1.f, &peak);
    EXPECT_NEAR(p.x(), 10.0 + ox, 0.1);
    const double sample = -k.at<float>(10, 10);
    EXPECT_NEAR(peak, height, 0.03 * height) << "offset " << ox;
    EXPECT_LE(std::fabs(peak - height), 0.5 * std::fabs(sample - height) + 1e-3) << "offset " << ox;
    if (ox > 0.4) {  // the sample alone falls short
      EXPECT_LT(sample, 0.93 * height);
    }
  }
}

TEST(PatchAlign, RecoversSubpixelTranslationUnderBrightnessOffset) {
  const int w = 160, h = 120;
  const auto blobs = randomBlobs(300, w, h, 21);
  const Eigen::Vector2d t(0.37, -0.61);
  auto smooth = [](const cv::Mat& g, double offset) {
    cv::Mat f;
    g.convertTo(f, CV_32F, 1.0, offset);
    cv::GaussianBlur(f, f, cv::Size(11, 11), 2.0, 2.0, cv::BORDER_REFLECT101);
    return f;
  };
  const cv::Mat a = smooth(renderBlobs(blobs, w, h, Eigen::Matrix2d::Identity(), Eigen::Vector2d::Zero()), 0.0);
  const cv::Mat b = smooth(renderBlobs(blobs, w, h, Eigen::Matrix2d::Identity(), t), 20.0);
  vt::PatchAlignParams params;
  params.radius = 3;
  params.iterations = 4;
  std::vector<double> err;
  for (int y = 20; y < h - 20; y += 9) {
    for (int x = 20; x < w - 20; x += 9) {
      const Eigen::Vector2f p0(static_cast<float>(x) + 0.2f, static_cast<float>(y) - 0.3f);
      Eigen::Vector2f p = p0;  // start at the old position: 0.7 px off
      if (!vt::alignPatch(a, b, p0, params, &p)) continue;
      err.push_back((p.cast<double>() - (p0.cast<double>() + t)).norm());
    }
  }
  ASSERT_GT(err.size(), 100u);
  std::sort(err.begin(), err.end());
  EXPECT_LT(err[err.size() / 2], 0.03);
  EXPECT_LT(err[err.size() * 9 / 10], 0.1);
  // No texture: singular normal matrix.
  const cv::Mat flat(h, w, CV_32F, cv::Scalar(100.f));
  Eigen::Vector2f q(50.f, 50.f);
  EXPECT_FALSE(vt::alignPatch(flat, flat, q, params, &q));
  EXPECT_EQ(q, Eigen::Vector2f(50.f, 50.f));
  // Leaving the image.
  Eigen::Vector2f r(2.f, 50.f);
  EXPECT_FALSE(vt::alignPatch(a, b, r, params, &r));
}

// min_track_sharpness ends the tracks whose kappa peak is flat in one
// direction: more of them with a higher threshold, none with an absurd one.
TEST(DenseTracker, SharpnessCheckEndsTracksOnFlatPeaks) {
  const int w = 320, h = 240;
  const auto blobs = randomBlobs(700, w, h, 19);
  const cv::Mat i0 = renderBlobs(blobs, w, h, Eigen::Matrix2d::Identity(), Eigen::Vector2d::Zero());
  const cv::Mat i1 = renderBlobs(blobs, w, h, Eigen::Matrix2d::Identity(), Eigen::Vector2d(1.7, 0.6));
  auto tracked = [&](double sharpness) {
    vt::TrackerConfig cfg;
    cfg.brief_scale = 1.0 / 3.0;
    cfg.brief_patch_size = 11;
    cfg.min_track_sharpness = sharpness;
    vt::DenseTracker tracker(cfg);
    tracker.track(i0, 0.0);
    return tracker.track(i1, 0.05).num_tracked;
  };
  const int n0 = tracked(0.0), n1 = tracked(0.05), n2 = tracked(0.2), n3 = tracked(100.0);
  EXPECT_GT(n0, 300);
  EXPECT_LT(n1, n0);
  EXPECT_LT(n2, n1);
  EXPECT_GT(n2, 0);
  EXPECT_EQ(n3, 0);
}

// On noisy images the extremum position jitters from frame to frame; the patch
// alignment carries the previous position over, and reporting the midpoint
// (extremum_weight 0.5) must cut the steps off by > 1 px by at least half
// (measured: 5.2 % of the tracks with the extremum alone, 1.4 % filtered) and
// shorten the tail of the errors, without losing tracks. (The median is not
// compared: here the flow prediction is exact, so prediction_blend, which the
// filter replaces, is at its best.)
TEST(DenseTracker, PatchFilterReducesJitterOnNoisyImages) {
  const int w = 320, h = 240;
  const auto blobs = randomBlobs(700, w, h, 17);
  const Eigen::Vector2d t(2.3, -1.4);
  const cv::Mat i0 = withNoise(renderBlobs(blobs, w, h, Eigen::Matrix2d::Identity(), Eigen::Vector2d::Zero()), 1);
  const cv::Mat i1 = withNoise(renderBlobs(blobs, w, h, Eigen::Matrix2d::Identity(), t), 2);
  auto run = [&](const vt::TrackerConfig& cfg, std::vector<double>* err) {
    vt::DenseTracker tracker(cfg);
    const auto f0 = tracker.track(i0, 0.0);
    const auto f1 = tracker.track(i1, 0.05);
    std::map<std::uint64_t, Eigen::Vector2f> before;
    for (const auto& p : f0.points) before[p.id] = p.uv;
    for (const auto& p : f1.points) {
      if (p.age > 0) err->push_back((p.uv.cast<double>() - (before[p.id].cast<double>() + t)).norm());
    }
    std::sort(err->begin(), err->end());
  };
  vt::TrackerConfig on;
  on.brief_scale = 1.0 / 3.0;
  on.brief_patch_size = 11;
  on.extremum_weight = 0.5;
  on.max_align_disagreement_px = 0.0;  // the filter alone: the confirmation has its own test
  vt::TrackerConfig off = on;
  off.extremum_weight = 1.0;
  std::vector<double> e_on, e_off;
  run(on, &e_on);
  run(off, &e_off);
  ASSERT_GT(e_off.size(), 200u);
  EXPECT_EQ(e_on.size(), e_off.size());
  auto bad = [](const std::vector<double>& e) {
    return static_cast<double>(std::count_if(e.begin(), e.end(), [](double x) { return x > 1.0; })) /
           static_cast<double>(e.size());
  };
  EXPECT_GT(bad(e_off), 0.02);
  EXPECT_LT(bad(e_on), 0.5 * bad(e_off));
  EXPECT_LT(e_on[e_on.size() * 95 / 100], e_off[e_off.size() * 95 / 100]);
}

// The confirmation by patch alignment (max_align_disagreement_px): on noisy
// images some climbs land on a neighbouring extremum; the patch, aligned from
// the flow prediction, disagrees with them and they end. Fewer steps off by
// more than 1 px (none here with the default patch filter, so: not more), most
// tracks kept, and the lost ones are counted as "unconfirmed". On an unrelated second image the climb still finds extrema
// near every prediction: the confirmation must end nearly all of those tracks.
TEST(DenseTracker, PatchConfirmationEndsJumpedTracks) {
  const int w = 320, h = 240;
  const auto blobs = randomBlobs(700, w, h, 17);
  const Eigen::Vector2d t(2.3, -1.4);
  const cv::Mat i0 = withNoise(renderBlobs(blobs, w, h, Eigen::Matrix2d::Identity(), Eigen::Vector2d::Zero()), 1);
  const cv::Mat i1 = withNoise(renderBlobs(blobs, w, h, Eigen::Matrix2d::Identity(), t), 2);
  const cv::Mat other =
      withNoise(renderBlobs(randomBlobs(700, w, h, 99), w, h, Eigen::Matrix2d::Identity(), Eigen::Vector2d::Zero()), 3);
  struct Result {
    std::vector<double> err;
    int tracked = 0, unconfirmed = 0;
  };
  auto run = [&](const vt::TrackerConfig& cfg, const cv::Mat& second) {
    Result r;
    vt::DenseTracker tracker(cfg);
    const auto f0 = tracker.track(i0, 0.0);
    const auto f1 = tracker.track(second, 0.05);
    std::map<std::uint64_t, Eigen::Vector2f> before;
    for (const auto& p : f0.points) before[p.id] = p.uv;
    for (const auto& p : f1.points) {
      if (p.age > 0) r.err.push_back((p.uv.cast<double>() - (before[p.id].cast<double>() + t)).norm());
    }
    r.tracked = f1.num_tracked;
    const auto it = f1.lost_by.find("unconfirmed");
    r.unconfirmed = it == f1.lost_by.end() ? 0 : it->second;
    return r;
  };
  vt::TrackerConfig on;
  on.brief_scale = 1.0 / 3.0;
  on.brief_patch_size = 11;
  on.max_align_disagreement_px = 0.75;
  vt::TrackerConfig off = on;
  off.max_align_disagreement_px = 0.0;
  const Result r_on = run(on, i1), r_off = run(off, i1);
  ASSERT_GT(r_off.tracked, 200);
  auto bad = [](const std::vector<double>& e) {
    return static_cast<double>(std::count_if(e.begin(), e.end(), [](double x) { return x > 1.0; })) /
           static_cast<double>(e.size());
  };
  EXPECT_LE(bad(r_on.err), bad(r_off.err));
  EXPECT_GT(r_on.tracked, 0.8 * r_off.tracked);
  EXPECT_GT(r_on.unconfirmed, 0);
  EXPECT_EQ(r_off.unconfirmed, 0);
  // Unrelated content: the climbs alone keep some tracks, the confirmation almost none.
  const Result u_on = run(on, other), u_off = run(off, other);
  EXPECT_GT(u_off.tracked, 10);
  EXPECT_LT(u_on.tracked, 0.25 * u_off.tracked);
  // Suspended when the patch fails for more than the allowed fraction of the tracks.
  vt::TrackerConfig suspended = on;
  suspended.confirm_max_unaligned_fraction = 0.0;
  EXPECT_EQ(run(suspended, other).tracked, u_off.tracked);
}

TEST(Brief, DistanceUnchangedByBrightnessOffset) {
  const int w = 120, h = 100;
  const auto blobs = randomBlobs(400, w, h, 5);
  const cv::Mat img = renderBlobs(blobs, w, h, Eigen::Matrix2d::Identity(), Eigen::Vector2d::Zero());
  cv::Mat brighter;
  img.convertTo(brighter, CV_32F, 1.0, 25.0);
  cv::Mat base;
  img.convertTo(base, CV_32F);
  vt::BriefExtractor brief(15);
  int compared = 0;
  for (int y = 20; y < 80; y += 13) {
    for (int x = 20; x < 100; x += 11) {
      vt::BriefDescriptor a, b, other;
      ASSERT_TRUE(brief.describe(base, x, y, &a));
      ASSERT_TRUE(brief.describe(brighter, x, y, &b));
      EXPECT_EQ(vt::hammingDistance(a, b), 0);
      ASSERT_TRUE(brief.describe(base, x + 9, y + 4, &other));
      EXPECT_GT(vt::hammingDistance(a, other), 40);  // a different patch is far
      ++compared;
    }
  }
  EXPECT_GT(compared, 20);
  // Out of the image: no descriptor.
  vt::BriefDescriptor d;
  EXPECT_FALSE(brief.describe(base, 3, 50, &d));
}

// matchBrief's definition, one pass over the whole distance matrix with a sign
// test per pair: what the matcher must return, ties included.
std::vector<std::pair<int, int>> matchBriefByDefinition(const std::vector<vt::BriefDescriptor>& a,
                                                        const std::vector<vt::BriefDescriptor>& b,
                                                        const vt::MatchConfig& c, const std::vector<signed char>* sa,
                                                        const std::vector<signed char>* sb) {
  const bool use_sign = sa && sb && sa->size() == a.size() && sb->size() == b.size();
  std::vector<int> best_a(a.size(), -1), d1_a(a.size(), INT_MAX), d2_a(a.size(), INT_MAX);
  std::vector<int> best_b(b.size(), -1), d1_b(b.size(), INT_MAX);
  for (size_t i = 0; i < a.size(); ++i) {
    for (size_t j = 0; j < b.size(); ++j) {
      if (use_sign && (*sa)[i] != (*sb)[j]) continue;
      const int d = vt::hammingDistance(a[i], b[j]);
      if (d < d1_a[i]) {
        d2_a[i] = d1_a[i];
        d1_a[i] = d;
        best_a[i] = static_cast<int>(j);
      } else if (d < d2_a[i]) {
        d2_a[i] = d;
      }
      if (d < d1_b[j]) {
        d1_b[j] = d;
        best_b[j] = static_cast<int>(i);
      }
    }
  }
  std::vector<std::pair<int, int>> out;
  for (size_t i = 0; i < a.size(); ++i) {
    const int j = best_a[i];
    if (j < 0 || d1_a[i] > c.max_distance) continue;
    if (c.ratio < 1.0 && d2_a[i] != INT_MAX && d1_a[i] >= c.ratio * d2_a[i]) continue;
    if (c.cross_check && best_b[static_cast<size_t>(j)] != static_cast<int>(i)) continue;
    out.emplace_back(static_cast<int>(i), j);
  }
  return out;
}

// The matcher visits only the blocks of equal signs: the same pairs as the
// definition, for every config, with and without signs, on descriptors that
// tie often (few bits apart from a handful of patterns).
TEST(Brief, MatchingByBlocksOfEqualSignsIsTheDefinition) {
  std::mt19937 rng(7);
  std::uniform_int_distribution<std::uint64_t> word;
  std::vector<vt::BriefDescriptor> patterns(6);
  for (auto& p : patterns) {
    for (auto& w : p.bits) w = word(rng);
  }
  const auto draw = [&](int n, std::vector<signed char>* sign) {
    std::vector<vt::BriefDescriptor> out(static_cast<size_t>(n));
    for (auto& d : out) {
      d = patterns[rng() % patterns.size()];
      for (int k = static_cast<int>(rng() % 4); k > 0; --k) d.bits[rng() % 4] ^= std::uint64_t{1} << (rng() % 64);
      sign->push_back(rng() % 2 ? 1 : -1);
    }
    return out;
  };
  int matched = 0;
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<signed char> sa, sb;
    const auto a = draw(40 + trial * 7, &sa), b = draw(30 + trial * 11, &sb);
    std::vector<signed char> sb_short(sb.begin(), sb.end() - 1);  // sizes differ: no sign test
    for (const vt::MatchConfig c : {vt::MatchConfig{70, 0.9, true}, vt::MatchConfig{2, 1.0, false},
                                    vt::MatchConfig{256, 1.0, true}, vt::MatchConfig{3, 0.8, false}}) {
      for (const std::vector<signed char>* sb_used : {&sb, &sb_short}) {
        const auto got = vt::matchBrief(a, b, c, &sa, sb_used);
        EXPECT_EQ(got, matchBriefByDefinition(a, b, c, &sa, sb_used)) << "trial " << trial;
        matched += static_cast<int>(got.size());
      }
      EXPECT_EQ(vt::matchBrief(a, b, c), matchBriefByDefinition(a, b, c, nullptr, nullptr));
    }
  }
  EXPECT_GT(matched, 200);  // not a comparison of empty lists
  EXPECT_TRUE(vt::matchBrief({}, patterns, vt::MatchConfig{}).empty());
}

TEST(Brief, SameBitsForEveryLayoutOfTheImage) {
  // The tests read the patch through the image's row stride: an 8-bit image and its float copy,
  // a window of a larger image (rows longer than the window) and the image turned by 180
  // degrees (described by the turned pattern) all give the same descriptor.
  const int w = 120, h = 100;
  const cv::Mat img =
      renderBlobs(randomBlobs(400, w, h, 6), w, h, Eigen::Matrix2d::Identity(), Eigen::Vector2d::Zero());
  cv::Mat img8;
  img.convertTo(img8, CV_8U);
  cv::Mat img32;
  img8.convertTo(img32, CV_32F);
  cv::Mat padded(h + 10, w + 37, CV_8UC1, cv::Scalar(0));
  img8.copyTo(padded(cv::Rect(5, 3, w, h)));
  const cv::Mat window = padded(cv::Rect(5, 3, w, h));
  ASSERT_FALSE(window.isContinuous());
  cv::Mat turned;
  cv::rotate(img8, turned, cv::ROTATE_180);
  const vt::BriefExtractor brief(15), brief_turned = brief.rotated(2);
  int described = 0;
  for (int y = 8; y < h - 8; y += 7) {
    for (int x = 8; x < w - 8; x += 9) {
      vt::BriefDescriptor a, b, c, d;
      ASSERT_TRUE(brief.describe(img8, x, y, &a));
      ASSERT_TRUE(brief.describe(img32, x, y, &b));
      ASSERT_TRUE(brief.describe(window, x, y, &c));
      ASSERT_TRUE(brief_turned.describe(turned, w - 1 - x, h - 1 - y, &d));
      EXPECT_EQ(a.bits, b.bits);
      EXPECT_EQ(a.bits, c.bits);
      EXPECT_EQ(a.bits, d.bits);
      described += a.bits != vt::BriefDescriptor{}.bits;
    }
  }
  EXPECT_GT(described, 50);  // textured patches, not all-zero descriptors
  vt::BriefDescriptor flat;
  ASSERT_TRUE(brief.describe(cv::Mat(h, w, CV_8UC1, cv::Scalar(90)), 50, 50, &flat));
  EXPECT_EQ(flat.bits, vt::BriefDescriptor{}.bits);  // no test is "less" on a constant patch
}

TEST(DenseTracker, BlackAndConstantImagesGiveNoFeatures) {
  vt::DenseTracker tracker;
  for (int v : {0, 0, 128, 255, 0}) {
    const cv::Mat img(480, 752, CV_8UC1, cv::Scalar(v));
    vt::TrackerFrame f;
    ASSERT_NO_THROW(f = tracker.track(img, 1.0));
    EXPECT_TRUE(f.points.empty());
    EXPECT_EQ(f.num_new, 0);
    EXPECT_FALSE(f.flow_ok);
  }
  EXPECT_THROW(tracker.track(cv::Mat(), 0.0), std::invalid_argument);
  EXPECT_THROW(tracker.track(cv::Mat(480, 752, CV_8UC3, cv::Scalar(1, 2, 3)), 0.0), std::invalid_argument);
  EXPECT_THROW(tracker.track(cv::Mat(480, 752, CV_32FC1, cv::Scalar(1)), 0.0), std::invalid_argument);
}

TEST(DenseTracker, SmoothsMoreOnNoisyImages) {
  const int w = 320, h = 240;
  const auto blobs = randomBlobs(700, w, h, 13);
  const cv::Mat clean = renderBlobs(blobs, w, h, Eigen::Matrix2d::Identity(), Eigen::Vector2d::Zero());
  cv::Mat noise(h, w, CV_32F), noisy;
  cv::randn(noise, 0.0, 12.0);
  clean.convertTo(noisy, CV_32F);
  noisy += noise;
  noisy.convertTo(noisy, CV_8U);
  vt::TrackerConfig cfg;
  vt::DenseTracker a(cfg), b(cfg);
  const auto fc = a.track(clean, 0.0);
  const auto fn = b.track(noisy, 0.0);
  EXPECT_DOUBLE_EQ(fc.smoothing_sigma, cfg.smoothing_sigma);
  EXPECT_GT(fn.noise_ratio, 2.0 * fc.noise_ratio);
  EXPECT_GT(fn.smoothing_sigma, cfg.smoothing_sigma);
  EXPECT_LE(fn.smoothing_sigma, cfg.max_smoothing_sigma);
  cfg.adaptive_smoothing = false;
  vt::DenseTracker c(cfg);
  EXPECT_DOUBLE_EQ(c.track(noisy, 0.0).smoothing_sigma, cfg.smoothing_sigma);
}

TEST(TrackerConfig, ValidateNamesTheField) {
  vt::TrackerConfig c;
  EXPECT_NO_THROW(c.validate());
  c.brief_scale = 0.0;
  try {
    c.validate();
    FAIL() << "expected invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("brief_scale"), std::string::npos);
  }
  c = vt::TrackerConfig{};
  c.extremum_weight = 0.0;
  try {
    c.validate();
    FAIL() << "expected invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("extremum_weight"), std::string::npos);
  }
  c = vt::TrackerConfig{};
  c.align_radius_px = 5;
  EXPECT_THROW(c.validate(), std::invalid_argument);
  c = vt::TrackerConfig{};
  c.threads = 0;
  EXPECT_THROW(vt::DenseTracker{c}, std::invalid_argument);
}

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
