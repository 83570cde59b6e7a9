#include "vitamin_e/tracking/dense_tracker.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <opencv2/imgproc.hpp>

#include "tracker_internal.h"
#include "vitamin_e/common/rounding.h"
#include "vitamin_e/common/timing.h"
#include "vitamin_e/tracking/affine_flow.h"
#include "vitamin_e/tracking/brief.h"
#include "vitamin_e/tracking/curvature.h"
#include "vitamin_e/tracking/patch_align.h"

namespace vitamin_e::tracking {
namespace {

struct Track {
  std::uint64_t id = 0;
  Eigen::Vector2f uv = Eigen::Vector2f::Zero();
  int age = 0;
  float sign = 1.f;
  float strength = 0.f;                             // normalized |kappa| at the last position
  float birth_exposure = 0.f;                       // Impl::exposure_log when the track was detected
  Eigen::Vector2f resid = Eigen::Vector2f::Zero();  // last motion minus the dominant flow (parallax)
};

// Result of tracking one point into the current frame.
struct Step {
  Eigen::Vector2f uv;
  Eigen::Vector2f ext;    // sub-pixel extremum (uv may be filtered)
  Eigen::Vector2f pred;   // flow prediction x_bar
  Eigen::Vector2f patch;  // the previous position carried over by patch alignment (if aligned)
  bool aligned = false;
  float gain = 1.f;  // contrast gain fitted by that alignment
  Eigen::Vector2i px;
  float kappa = 0.f;
  float peak = 0.f;      // sign*kappa of the sub-pixel peak
  bool climbed = false;  // the forward climb reached a maximum (peak is valid)
  bool ok = false;
  int fail = 0;  // LossReason of a failed step (kLossOk when ok)
};

// Why a track step failed; counted per frame in TrackerFrame::lost_by.
enum LossReason : int {
  kLossOk = 0,
  kLossClimb,
  kLossWeak,
  kLossStrengthChange,
  kLossFlat,
  kLossBackClimb,
  kLossForwardBackward,
  kLossUnconfirmed,
  kLossDuplicate,
  kLossReasons
};
// An absolute floor that follows the exposure (floor_follows_exposure) drops by
// at most this factor: a darker change than that (a covered lens) ends tracks.
constexpr float kMaxFloorDrop = 16.f;
// strength_follows_prior_scale: the band widens by at most this factor, and a
// track lost to the strength check is retried from its prior only when it widens
// by more than the other one.
constexpr float kMaxPriorWiden = 4.f;
constexpr float kMinPriorWidenToRetry = 1.05f;

const char* const kLossNames[kLossReasons] = {
    "ok", "climb", "weak", "strength_change", "flat", "back_climb", "forward_backward", "unconfirmed", "duplicate"};


}  // namespace

struct DenseTracker::Impl {
  TrackerConfig cfg;
  BriefExtractor brief;
  std::uint64_t next_id = 1;
  bool has_prev = false;
  cv::Size size;
  cv::Mat prev_kappa, kappa;
  cv::Mat prev_smooth, smooth;  // pre-smoothed float images (for the patch alignment)
  float prev_scale = 0.f;
  SmallFeatures prev_small, small;
  std::vector<Track> tracks, next_tracks;
  std::vector<Step> steps;
  cv::Mat owner;    // CV_32SC1: index+1 of the surviving track at a pixel, 0 = none
  cv::Mat blocked;  // CV_8UC1: 1 within nms radius of a surviving track
  std::vector<Extremum> cands;
  std::vector<int> cell_count, cell_slots;
  std::vector<float> scratch;
  double sigma_state = 0.0;    // smoothed adaptive sigma (0 = not yet set)
  float strength_ratio = 1.f;  // this frame's median new/old strength of the climbed tracks
  float exposure_log = 0.f;    // sum over frames of log(median raw peak ratio): log of the contrast change cubed
  float exposure_step = 0.f;   // this frame's part of it (set by trackAll)
  float patch_gain = 1.f;      // this frame's median contrast gain of the patch alignment
  std::vector<float> ratios;   // scratch of frameStrengthRatio / alignSteps

  // The frame rate: after dropped frames the tracks' parallax step is longer.
  double last_t = std::nan("");         // stamp of the previous frame [s]
  double last_interval = std::nan("");  // the gap before it [s]
  float parallax_scale = 1.f;           // this frame's gap over that one (frameGapRatio)

  // A track's predicted parallax step: its last residual to the dominant flow,
  // scaled to this frame's gap.
  Eigen::Vector2f parallaxOf(const Track& t) const {
    return cfg.predict_parallax ? Eigen::Vector2f(parallax_scale * t.resid) : Eigen::Vector2f::Zero();
  }

  // The caller's priors, per track (index as tracks; empty when there are
  // none): a track with from_prior set is predicted at prior_uv instead of by the flow.
  std::vector<Eigen::Vector2f> prior_uv;
  std::vector<std::uint8_t> has_prior, from_prior;
  std::vector<float> prior_widen;  // strength_follows_prior_scale: the strength band's factor per track
  std::vector<int> retry;
  std::vector<Eigen::Vector2d> match_prev, match_cur;  // this frame's BRIEF matches, previous -> this [px]
  bool fromPrior(int i) const { return !from_prior.empty() && from_prior[static_cast<size_t>(i)]; }

  explicit Impl(const TrackerConfig& c) : cfg(c), brief(c.brief_patch_size) {}

  // subset: the tracks to step (indices into tracks); null: all of them.
  void trackAll(const Eigen::Matrix2d& A, const Eigen::Vector2d& b, float scale,
                const std::vector<int>* subset = nullptr);
  float frameStrengthRatio(float scale);
  int detect(const cv::Mat& gray, float scale, std::vector<Track>* fresh);
  void alignSteps(const std::vector<int>* subset = nullptr);
  void matchPriors(const std::vector<TrackPrior>& priors);
  void retryFromPriors(const Eigen::Matrix2d& A, const Eigen::Vector2d& b, float scale, bool align);
};

void DenseTracker::Impl::trackAll(const Eigen::Matrix2d& A, const Eigen::Vector2d& b, float scale,
                                  const std::vector<int>* subset) {
  const Eigen::Matrix2f Af = A.cast<float>();
  const Eigen::Vector2f bf = b.cast<float>();
  const Eigen::Matrix2d Ainv_d =
      std::fabs(A.determinant()) > 1e-6 ? Eigen::Matrix2d(A.inverse()) : Eigen::Matrix2d::Identity();
  const Eigen::Matrix2f Ainv = Ainv_d.cast<float>();
  const float sigma2 = static_cast<float>(cfg.track_sigma_px * cfg.track_sigma_px);
  const float fb2 = static_cast<float>(cfg.fb_threshold_px * cfg.fb_threshold_px);
  const float inv_scale = 1.f / scale;
  const float max_ratio = static_cast<float>(cfg.max_curvature_ratio);
  const float blend = static_cast<float>(cfg.prediction_blend);
  const float min_sharp = static_cast<float>(cfg.min_track_sharpness);
  const int stripes = cfg.threads > 1 ? cfg.threads * 4 : 1;
  steps.resize(tracks.size());
  const int count = subset ? static_cast<int>(subset->size()) : static_cast<int>(tracks.size());
  const auto index = [subset](int k) { return subset ? (*subset)[static_cast<size_t>(k)] : k; };
  // Forward: climb F from the flow prediction to a local maximum.
  auto climb = [&](int k0, int k1) {
    for (int k = k0; k < k1; ++k) {
      const int i = index(k);
      const Track& t = tracks[i];
      Step& s = steps[i];
      s.ok = false;
      s.climbed = false;
      s.fail = kLossClimb;
      ClimbParams fwd{t.sign, static_cast<float>(cfg.lambda) * scale, sigma2, cfg.max_climb_steps, 2};
      const Eigen::Vector2f pred = fromPrior(i) ? prior_uv[i] : Eigen::Vector2f(Af * t.uv + bf + parallaxOf(t));
      s.pred = pred;
      if (!hillClimb(kappa, pred, fwd, &s.px)) continue;
      if (cfg.polish_steps > 0) {
        // The prior biases the maximum of F; the extremum is the maximum of kappa.
        const ClimbParams pol{t.sign, 0.f, 1.f, cfg.polish_steps, 2};
        if (!hillClimb(kappa, s.px.cast<float>(), pol, &s.px)) continue;
      }
      s.kappa = kappa.ptr<float>(s.px.y())[s.px.x()];
      float peak = t.sign * s.kappa;
      s.uv = refineSubpixel(kappa, s.px, t.sign, &peak);
      if (!cfg.strength_at_subpixel_peak) peak = t.sign * s.kappa;
      s.peak = peak;
      s.climbed = true;
    }
  };
  forStripes(count, stripes, 257, climb);
  // The frame's strength change: an exposure step scales every peak alike (by
  // about the cube of the brightness ratio: kappa is cubic in intensity), which
  // the noise-dominated median |kappa| does not follow; each track is then
  // judged against that common change, not against 1.
  if (!subset) strength_ratio = frameStrengthRatio(scale);
  // Ordinary frames scatter by a few % about 1 (motion, blur): there the test
  // stays against 1, as before; it moves only on a real step.
  const float test_ratio =
      std::fabs(std::log(strength_ratio)) > std::log1p(static_cast<float>(cfg.strength_ratio_min_change))
          ? strength_ratio
          : 1.f;
  // The single tracks scatter more about that change when it is large (the
  // exposure time, hence the motion blur, changes with it, and so do the noise
  // share and the saturation): the band widens by the change itself, by at most
  // max_ratio again (a change beyond that is no exposure step).
  const float widen = std::min(std::max(test_ratio, 1.f / test_ratio), max_ratio);
  const float ratio_lo = test_ratio / (max_ratio * widen), ratio_hi = test_ratio * max_ratio * widen;
  // The frame's raw curvature change (~ contrast gain cubed) accumulates into
  // exposure_log; the absolute floor of a track follows it since the track's
  // birth (see floor_follows_exposure).
  const float raw_ratio = strength_ratio * scale / prev_scale;
  const float exposure_now = exposure_log + (std::isfinite(raw_ratio) && raw_ratio > 0.f ? std::log(raw_ratio) : 0.f);
  const float min_rel = static_cast<float>(cfg.min_track_curvature) * scale;
  const float floor_abs = static_cast<float>(cfg.min_abs_curvature);
  const float floor_min_log = -std::log(kMaxFloorDrop);
  exposure_step = exposure_now - exposure_log;
  auto check = [&](int k0, int k1) {
    for (int k = k0; k < k1; ++k) {
      const int i = index(k);
      const Track& t = tracks[i];
      Step& s = steps[i];
      if (!s.climbed) continue;
      const float peak = s.peak;
      s.fail = kLossWeak;
      float floor_k = floor_abs;
      if (cfg.floor_follows_exposure && peak < floor_abs) {  // the factor is <= 1
        floor_k *= std::exp(std::clamp(exposure_now - t.birth_exposure, floor_min_log, 0.f));
      }
      if (peak < std::max(min_rel, floor_k)) continue;
      const float strength = peak * inv_scale;
      s.fail = kLossStrengthChange;
      // A size change the prior predicts moves the peak: the band widens by it (strength_follows_prior_scale).
      const float wp = fromPrior(i) ? prior_widen[i] : 1.f;
      if (strength > t.strength * ratio_hi * wp || strength < t.strength * ratio_lo / wp) continue;
      s.fail = kLossFlat;
      if (min_sharp > 0.f && peakSharpness(kappa, s.px, t.sign) < min_sharp) continue;
      // Backward: climb the previous curvature from the inverse prediction.
      const Eigen::Vector2f back_pred =
          fromPrior(i) ? Eigen::Vector2f(s.uv - (s.pred - t.uv)) : Eigen::Vector2f(Ainv * (s.uv - bf - parallaxOf(t)));
      ClimbParams bwd{t.sign, static_cast<float>(cfg.lambda) * prev_scale, sigma2, cfg.max_climb_steps, 2};
      Eigen::Vector2i q;
      s.fail = kLossBackClimb;
      if (!hillClimb(prev_kappa, back_pred, bwd, &q)) continue;
      if (cfg.polish_steps > 0) {
        const ClimbParams pol{t.sign, 0.f, 1.f, cfg.polish_steps, 2};
        if (!hillClimb(prev_kappa, q.cast<float>(), pol, &q)) continue;
      }
      const Eigen::Vector2f qs = refineSubpixel(prev_kappa, q, t.sign);
      s.ok = (qs - t.uv).squaredNorm() <= fb2;
      s.fail = s.ok ? kLossOk : kLossForwardBackward;
      s.ext = s.uv;
      if (s.ok && blend > 0.f && (s.pred - s.uv).squaredNorm() < 1.f) s.uv += blend * (s.pred - s.uv);
    }
  };
  forStripes(count, stripes, 257, check);
}

void DenseTracker::Impl::matchPriors(const std::vector<TrackPrior>& priors) {
  retry.clear();
  from_prior.clear();
  if (priors.empty() || !cfg.retry_from_prior) {
    has_prior.clear();
    return;
  }
  const size_t n = tracks.size();
  prior_uv.assign(n, Eigen::Vector2f::Zero());
  prior_widen.assign(n, 1.f);
  has_prior.assign(n, 0);
  from_prior.assign(n, 0);
  for (size_t i = 0; i < n; ++i) {
    const auto it = std::lower_bound(priors.begin(), priors.end(), tracks[i].id,
                                     [](const TrackPrior& p, std::uint64_t id) { return p.id < id; });
    if (it == priors.end() || it->id != tracks[i].id || !it->uv.allFinite()) continue;
    prior_uv[i] = it->uv;
    if (cfg.strength_follows_prior_scale && it->scale > 0.f && std::isfinite(it->scale)) {
      prior_widen[i] = std::min(std::max(it->scale, 1.f / it->scale), kMaxPriorWiden);
    }
    has_prior[i] = 1;
  }
}

// The tracks the flow's prediction lost get one more step from their prior
// where that is elsewhere: after dropped frames one affine flow cannot predict
// both a near and a far layer, a map point seen from the predicted pose can.
// The step passes the same checks; the flow stays the frame's flow.
void DenseTracker::Impl::retryFromPriors(const Eigen::Matrix2d& A, const Eigen::Vector2d& b, float scale, bool align) {
  retry.clear();
  if (has_prior.empty()) return;
  bool any_lost = false;
  for (size_t i = 0; i < tracks.size() && !any_lost; ++i) any_lost = has_prior[i] && !steps[i].ok;
  if (!any_lost) return;
  // The predicted pose is off by the motion model's error (a turn that starts or ends), the
  // same for every layer. Each BRIEF match moved as the nearest map track's prior says, up to
  // that error: a robust affine from those predictions to the matches corrects every prior.
  // (Not the map tracks the flow kept: where one flow cannot follow two layers most of them
  // climbed to the wrong extremum; docs/PERFORMANCE.md, "Dropped frames".)
  std::vector<Eigen::Vector2d> xs, ys;
  const int cell = 16;  // [px]: a match farther than this from every map track is not used
  const int gw = size.width / cell + 1, gh = size.height / cell + 1;
  const auto at = [gw](int x, int y) {
    return static_cast<size_t>(y) * static_cast<size_t>(gw) + static_cast<size_t>(x);
  };
  std::vector<std::vector<int>> grid(at(0, gh));
  for (size_t i = 0; i < tracks.size(); ++i) {
    if (!has_prior[i]) continue;
    const int cx = std::clamp(static_cast<int>(tracks[i].uv.x()) / cell, 0, gw - 1);
    const int cy = std::clamp(static_cast<int>(tracks[i].uv.y()) / cell, 0, gh - 1);
    grid[at(cx, cy)].push_back(static_cast<int>(i));
  }
  for (size_t k = 0; k < match_prev.size(); ++k) {
    const Eigen::Vector2f q = match_prev[k].cast<float>();
    const int cx = std::clamp(static_cast<int>(q.x()) / cell, 0, gw - 1);
    const int cy = std::clamp(static_cast<int>(q.y()) / cell, 0, gh - 1);
    int best = -1;
    float best_d2 = static_cast<float>(cell * cell);
    for (int y = std::max(0, cy - 1); y <= std::min(gh - 1, cy + 1); ++y) {
      for (int x = std::max(0, cx - 1); x <= std::min(gw - 1, cx + 1); ++x) {
        for (int i : grid[at(x, y)]) {
          const float d2 = (tracks[static_cast<size_t>(i)].uv - q).squaredNorm();
          if (d2 < best_d2) best_d2 = d2, best = i;
        }
      }
    }
    if (best < 0) continue;
    const size_t t = static_cast<size_t>(best);
    xs.push_back((q + prior_uv[t] - tracks[t].uv).cast<double>());
    ys.push_back(match_cur[k]);
  }
  const AffineFitConfig fc{cfg.flow_sigma_start_px, 1.0, 3, std::max(cfg.flow_min_matches, 30)};
  const AffineFit fix = fitAffineGemanMcClure(xs, ys, fc);
  if (fix.ok) {
    const Eigen::Matrix2f Af = fix.A.cast<float>();
    const Eigen::Vector2f bf = fix.b.cast<float>();
    for (size_t i = 0; i < tracks.size(); ++i) {
      if (has_prior[i]) prior_uv[i] = Af * prior_uv[i] + bf;
    }
  }
  // The band in which the affine fit counts its inliers (affine_flow.cpp).
  const float min_d2 = static_cast<float>(std::pow(2.5 * cfg.flow_sigma_px, 2));
  for (size_t i = 0; i < tracks.size(); ++i) {
    if (steps[i].ok || !has_prior[i]) continue;
    // Ended by the strength check where the prior predicts a size change: once more, within the wider band.
    const bool rescaled = steps[i].fail == kLossStrengthChange && prior_widen[i] > kMinPriorWidenToRetry;
    if (!rescaled && (prior_uv[i] - steps[i].pred).squaredNorm() <= min_d2) continue;
    from_prior[i] = 1;
    retry.push_back(static_cast<int>(i));
  }
  if (retry.empty()) return;
  trackAll(A, b, scale, &retry);
  if (align) alignSteps(&retry);
}

float DenseTracker::Impl::frameStrengthRatio(float scale) {
  if (!cfg.relative_strength_change) return 1.f;
  ratios.clear();
  const float inv_scale = 1.f / scale;
  for (size_t i = 0; i < tracks.size(); ++i) {
    const Step& s = steps[i];
    if (!s.climbed || !(s.peak > 0.f) || !(tracks[i].strength > 0.f)) continue;
    ratios.push_back(s.peak * inv_scale / tracks[i].strength);
  }
  // Too few climbed tracks for a robust median: no common change assumed.
  if (ratios.size() < 30) return 1.f;
  auto mid = ratios.begin() + static_cast<long>(ratios.size() / 2);
  std::nth_element(ratios.begin(), mid, ratios.end());
  return std::isfinite(*mid) && *mid > 0.f ? *mid : 1.f;
}

void DenseTracker::Impl::alignSteps(const std::vector<int>* subset) {
  const float w = static_cast<float>(cfg.extremum_weight);
  // To confirm the climb, the patch alignment starts from the flow prediction,
  // not from the climbed extremum, so that it is an independent witness of where
  // the point went; as a filter alone it starts from the extremum (it converges
  // more often from there). It may move up to 1.5 px from its start.
  // On a frame whose contrast changed (exposure_step = log of the median raw
  // peak ratio ~ 3 log(gain)) it fits a contrast gain per patch too: an
  // unmodelled gain biases the shift. Elsewhere the mean alone (a gain fit there
  // only adds noise).
  const bool fit_gain =
      cfg.align_gain && std::fabs(exposure_step) > 3.f * std::log1p(static_cast<float>(cfg.align_gain_min_change));
  const PatchAlignParams ap{cfg.align_radius_px, cfg.align_iterations, 1.5f, fit_gain};
  const bool from_prediction = cfg.max_align_disagreement_px > 0.0;
  const int count = subset ? static_cast<int>(subset->size()) : static_cast<int>(tracks.size());
  const auto index = [subset](int k) { return subset ? (*subset)[static_cast<size_t>(k)] : k; };
  auto work = [&](int k0, int k1) {
    for (int k = k0; k < k1; ++k) {
      const int i = index(k);
      Step& s = steps[i];
      if (!s.ok) continue;
      s.patch = from_prediction ? s.pred : s.ext;
      s.aligned = alignPatch(prev_smooth, smooth, tracks[i].uv, ap, &s.patch, &s.gain);
    }
  };
  forStripes(count, cfg.threads > 1 ? cfg.threads * 4 : 1, 257, work);
  int candidates = 0, unaligned = 0;
  ratios.clear();
  for (int k = 0; k < count; ++k) {
    const Step& s = steps[index(k)];
    candidates += s.ok;
    unaligned += s.ok && !s.aligned;
    if (s.ok && s.aligned) ratios.push_back(s.gain);
  }
  if (!subset && !ratios.empty()) {
    auto mid = ratios.begin() + static_cast<long>(ratios.size() / 2);
    std::nth_element(ratios.begin(), mid, ratios.end());
    patch_gain = *mid;
  }
  // Confirmation: the extremum must lie within max_align_disagreement_px of the
  // patch's answer. Suspended on frames where the patch itself fails too often
  // (fast motion and blur change the appearance): there it would only thin out
  // the tracks the pose needs.
  const bool confirm =
      cfg.max_align_disagreement_px > 0.0 && unaligned <= cfg.confirm_max_unaligned_fraction * candidates;
  const float max_d2 = static_cast<float>(cfg.max_align_disagreement_px * cfg.max_align_disagreement_px);
  for (int k = 0; k < count; ++k) {
    Step& s = steps[index(k)];
    if (!s.ok) continue;
    if (confirm && (!s.aligned || (s.ext - s.patch).squaredNorm() > max_d2)) {
      s.ok = false;
      s.fail = kLossUnconfirmed;
      continue;
    }
    if (s.aligned) s.uv = s.patch + w * (s.ext - s.patch);
  }
}

int DenseTracker::Impl::detect(const cv::Mat& gray, float scale, std::vector<Track>* fresh) {
  fresh->clear();
  const int room = cfg.max_points - static_cast<int>(next_tracks.size());
  if (room <= 0 || scale <= 0.f) return 0;
  const float thr = std::max(static_cast<float>(cfg.min_curvature) * scale, static_cast<float>(cfg.min_abs_curvature));
  detectExtrema(kappa, cfg.nms_radius_px, thr, cfg.border_px, &cands, cfg.threads);
  const int cs = cfg.grid_cell_px, k = cfg.max_per_cell;
  const int gw = (gray.cols + cs - 1) / cs, gh = (gray.rows + cs - 1) / cs;
  cell_count.assign(static_cast<size_t>(gw) * gh, 0);
  cell_slots.assign(static_cast<size_t>(gw) * gh * k, -1);
  for (const Track& t : next_tracks) {
    const int x = common::roundHalfAway(t.uv.x()), y = common::roundHalfAway(t.uv.y());
    ++cell_count[(y / cs) * gw + x / cs];
  }
  for (int i = 0; i < static_cast<int>(cands.size()); ++i) {
    const Extremum& e = cands[i];
    if (blocked.ptr<std::uint8_t>(e.y)[e.x]) continue;
    const int c = (e.y / cs) * gw + e.x / cs;
    const int free_slots = k - cell_count[c];
    if (free_slots <= 0) continue;
    int* slots = &cell_slots[static_cast<size_t>(c) * k];
    // Keep the `free_slots` strongest candidates of the cell.
    int weakest = -1;
    for (int j = 0; j < free_slots; ++j) {
      if (slots[j] < 0) {
        weakest = j;
        break;
      }
      if (weakest < 0 || std::fabs(cands[slots[j]].kappa) < std::fabs(cands[slots[weakest]].kappa)) weakest = j;
    }
    if (slots[weakest] < 0 || std::fabs(cands[slots[weakest]].kappa) < std::fabs(e.kappa)) slots[weakest] = i;
  }
  std::vector<int> chosen;
  chosen.reserve(cell_slots.size());
  for (int s : cell_slots)
    if (s >= 0) chosen.push_back(s);
  if (static_cast<int>(chosen.size()) > room) {
    std::nth_element(chosen.begin(), chosen.begin() + room, chosen.end(),
                     [&](int a, int b) { return std::fabs(cands[a].kappa) > std::fabs(cands[b].kappa); });
    chosen.resize(room);
  }
  std::sort(chosen.begin(), chosen.end());
  fresh->reserve(chosen.size());
  for (int i : chosen) {
    const Extremum& e = cands[i];
    Track t;
    t.id = next_id++;
    t.sign = e.kappa > 0.f ? 1.f : -1.f;
    float peak = std::fabs(e.kappa);
    t.uv = refineSubpixel(kappa, Eigen::Vector2i(e.x, e.y), t.sign, &peak);
    if (!cfg.strength_at_subpixel_peak) peak = std::fabs(e.kappa);
    t.age = 0;
    t.strength = peak / scale;
    t.birth_exposure = exposure_log;
    fresh->push_back(t);
  }
  return static_cast<int>(fresh->size());
}

DenseTracker::DenseTracker(const TrackerConfig& config) {
  config.validate();
  impl_ = std::make_unique<Impl>(config);
}
DenseTracker::~DenseTracker() = default;
DenseTracker::DenseTracker(DenseTracker&&) noexcept = default;
DenseTracker& DenseTracker::operator=(DenseTracker&&) noexcept = default;

const TrackerConfig& DenseTracker::config() const { return impl_->cfg; }

void DenseTracker::reset() {
  impl_->has_prev = false;
  impl_->tracks.clear();
  impl_->prev_small = SmallFeatures{};
  impl_->prev_smooth.release();
  impl_->sigma_state = 0.0;
  impl_->exposure_log = 0.f;
}

void DenseTracker::reserveIdsBelow(std::uint64_t first_id) { impl_->next_id = std::max(impl_->next_id, first_id); }

std::size_t DenseTracker::dropTracks(const std::vector<std::uint64_t>& ids) {
  if (ids.empty()) return 0;
  std::vector<std::uint64_t> sorted(ids);
  std::sort(sorted.begin(), sorted.end());
  auto& tr = impl_->tracks;
  const std::size_t before = tr.size();
  tr.erase(std::remove_if(tr.begin(), tr.end(),
                          [&](const Track& t) { return std::binary_search(sorted.begin(), sorted.end(), t.id); }),
           tr.end());
  return before - tr.size();
}

TrackerFrame DenseTracker::track(const cv::Mat& gray, double timestamp, const std::vector<TrackPrior>& priors) {
  return track(gray, timestamp, PriorProvider([&priors] { return priors; }));
}

TrackerFrame DenseTracker::track(const cv::Mat& gray, double timestamp, const PriorProvider& priors) {
  if (gray.empty()) throw std::invalid_argument("DenseTracker::track: empty image");
  if (gray.type() != CV_8UC1) throw std::invalid_argument("DenseTracker::track: image must be CV_8UC1");
  Impl& m = *impl_;
  const TrackerConfig& cfg = m.cfg;
  if (gray.cols < 2 * cfg.border_px + 3 || gray.rows < 2 * cfg.border_px + 3) {
    throw std::invalid_argument("DenseTracker::track: image smaller than 2*border_px+3");
  }
  const auto t_all = TimingClock::now();
  TrackerFrame out;
  out.timestamp = timestamp;
  if (m.has_prev && gray.size() != m.size) reset();
  m.size = gray.size();
  m.parallax_scale = m.has_prev ? static_cast<float>(frameGapRatio(timestamp - m.last_t, m.last_interval)) : 1.f;
  m.last_interval = m.has_prev ? timestamp - m.last_t : std::nan("");
  m.last_t = timestamp;

  auto t = TimingClock::now();
  double sigma = cfg.smoothing_sigma;
  if (cfg.adaptive_smoothing) {
    out.noise_ratio = noiseToGradientRatio(gray, &m.scratch);
    const double target =
        std::clamp(cfg.smoothing_sigma * std::sqrt(std::max(1.0, out.noise_ratio / cfg.noise_reference)),
                   cfg.smoothing_sigma, cfg.max_smoothing_sigma);
    // Slow and quantized: consecutive curvature images stay comparable.
    m.sigma_state = m.sigma_state > 0.0 ? 0.8 * m.sigma_state + 0.2 * target : target;
    sigma = std::round(m.sigma_state * 4.0) / 4.0;
  }
  out.smoothing_sigma = sigma;
  const bool align = cfg.extremum_weight < 1.0;
  computeCurvature(gray, sigma, &m.kappa, cfg.threads, align ? &m.smooth : nullptr);
  if (cfg.kappa_smoothing_sigma > 0.0) {
    const int k = 2 * static_cast<int>(std::ceil(2.5 * cfg.kappa_smoothing_sigma)) + 1;
    cv::GaussianBlur(m.kappa, m.kappa, cv::Size(k, k), cfg.kappa_smoothing_sigma, cfg.kappa_smoothing_sigma,
                     cv::BORDER_REFLECT101);
  }
  const float scale = robustCurvatureScale(m.kappa);
  out.timing_ms["curvature"] = elapsedMs(t);

  // Dominant flow from BRIEF matches on the shrunk image.
  t = TimingClock::now();
  extractSmallFeatures(gray, cfg, m.brief, &m.small);
  Eigen::Matrix2d A = Eigen::Matrix2d::Identity();
  Eigen::Vector2d b = Eigen::Vector2d::Zero();  // no flow: identity
  m.match_prev.clear();
  m.match_cur.clear();
  if (m.has_prev) {
    MatchConfig mc{cfg.brief_max_distance, cfg.brief_ratio, true};
    const auto pairs = matchBrief(m.prev_small.desc, m.small.desc, mc, &m.prev_small.sign, &m.small.sign);
    // Kept for the priors' correction (retryFromPriors) as well as fitted here.
    m.match_prev.reserve(pairs.size());
    m.match_cur.reserve(pairs.size());
    for (const auto& p : pairs) {
      m.match_prev.push_back(m.prev_small.pos[p.first]);
      m.match_cur.push_back(m.small.pos[p.second]);
    }
    out.flow_matches = static_cast<int>(pairs.size());
    AffineFitConfig fc{cfg.flow_sigma_start_px, cfg.flow_sigma_px, cfg.flow_iterations, cfg.flow_min_matches};
    const AffineFit fit = fitAffineGemanMcClure(m.match_prev, m.match_cur, fc);
    if (fit.ok) {
      A = fit.A;
      b = fit.b;
      out.flow_ok = true;
    }
  }
  out.A = A;
  out.b = b;
  out.timing_ms["flow"] = elapsedMs(t);

  // Extrema tracking.
  t = TimingClock::now();
  m.next_tracks.clear();
  if (m.owner.size() != gray.size()) {
    m.owner = cv::Mat::zeros(gray.size(), CV_32SC1);
    m.blocked = cv::Mat::zeros(gray.size(), CV_8UC1);
  }
  m.strength_ratio = 1.f;
  m.patch_gain = 1.f;
  m.exposure_step = 0.f;
  if (m.has_prev && !m.tracks.empty() && scale > 0.f) {
    m.from_prior.clear();  // the flow's pass: no track is predicted from a prior
    m.trackAll(A, b, scale);
    if (cfg.refine_flow) {
      // Refit the dominant flow to the tracked extrema (thousands of precise
      // pairs) and track again from the refined prediction.
      std::vector<Eigen::Vector2d> xs, ys;
      xs.reserve(m.tracks.size());
      ys.reserve(m.tracks.size());
      for (size_t i = 0; i < m.tracks.size(); ++i) {
        if (!m.steps[i].ok) continue;
        const Eigen::Vector2f r = m.parallaxOf(m.tracks[i]);
        xs.push_back(m.tracks[i].uv.cast<double>());
        ys.push_back((m.steps[i].uv - r).cast<double>());
      }
      AffineFitConfig fc{std::max(cfg.flow_sigma_px, 1.0), 1.0, 3, std::max(cfg.flow_min_matches, 30)};
      const AffineFit fit = refineAffineGemanMcClure(xs, ys, A, b, fc);
      if (fit.ok) {
        A = fit.A;
        b = fit.b;
        out.A = A;
        out.b = b;
        out.flow_ok = true;
        m.trackAll(A, b, scale);
      }
    }
    const bool can_align = align && !m.prev_smooth.empty() && m.prev_smooth.size() == m.smooth.size();
    if (can_align) m.alignSteps();
    m.matchPriors(cfg.retry_from_prior && priors ? priors() : std::vector<TrackPrior>{});
    m.retryFromPriors(A, b, scale, can_align);
    for (int i : m.retry) out.num_from_prior += m.steps[i].ok ? 1 : 0;
    // Two tracks on one pixel: keep the older one.
    for (size_t i = 0; i < m.tracks.size(); ++i) {
      if (!m.steps[i].ok) continue;
      int& o = m.owner.ptr<int>(m.steps[i].px.y())[m.steps[i].px.x()];
      if (o == 0) {
        o = static_cast<int>(i) + 1;
      } else if (m.tracks[i].age > m.tracks[o - 1].age) {
        m.steps[o - 1].ok = false;
        m.steps[o - 1].fail = kLossDuplicate;
        o = static_cast<int>(i) + 1;
      } else {
        m.steps[i].ok = false;
        m.steps[i].fail = kLossDuplicate;
      }
    }
    for (size_t i = 0; i < m.tracks.size(); ++i) {
      const Step& s = m.steps[i];
      if (s.px.x() >= 0 && s.px.y() >= 0 && s.px.x() < gray.cols && s.px.y() < gray.rows) {
        m.owner.ptr<int>(s.px.y())[s.px.x()] = 0;
      }
      if (!s.ok) continue;
      Track tr = m.tracks[i];
      tr.resid = s.uv - (A.cast<float>() * tr.uv + b.cast<float>());
      tr.uv = s.uv;
      tr.age += 1;
      tr.strength = s.peak / scale;
      m.next_tracks.push_back(tr);
    }
    int counts[kLossReasons] = {}, young[kLossReasons] = {};
    for (size_t i = 0; i < m.tracks.size(); ++i) {
      const int why = m.steps[i].ok ? kLossOk : m.steps[i].fail;
      ++counts[why];
      if (m.tracks[i].age == 0) ++young[why];
      if (why != kLossOk) out.ended.emplace_back(m.tracks[i].id, kLossNames[why]);
    }
    for (int k = 1; k < kLossReasons; ++k) {
      if (counts[k] > 0) out.lost_by[kLossNames[k]] = counts[k];
      if (young[k] > 0) out.lost_new_by[kLossNames[k]] = young[k];
    }
  }
  m.exposure_log += m.exposure_step;
  out.curvature_scale = scale;
  out.strength_ratio = m.strength_ratio;
  out.patch_gain = m.patch_gain;
  out.num_lost = static_cast<int>(m.tracks.size() - m.next_tracks.size());
  out.num_tracked = static_cast<int>(m.next_tracks.size());
  out.timing_ms["track"] = elapsedMs(t);

  // New extrema where the grid has room.
  t = TimingClock::now();
  const int r = cfg.nms_radius_px;
  auto mark_blocked = [&](std::uint8_t v) {
    for (const Track& tr : m.next_tracks) {
      const int x = common::roundHalfAway(tr.uv.x()), y = common::roundHalfAway(tr.uv.y());
      for (int yy = std::max(0, y - r); yy <= std::min(gray.rows - 1, y + r); ++yy) {
        std::uint8_t* row = m.blocked.ptr<std::uint8_t>(yy);
        for (int xx = std::max(0, x - r); xx <= std::min(gray.cols - 1, x + r); ++xx) row[xx] = v;
      }
    }
  };
  mark_blocked(1);
  std::vector<Track> fresh;
  out.num_new = m.detect(gray, scale, &fresh);
  mark_blocked(0);
  m.next_tracks.insert(m.next_tracks.end(), fresh.begin(), fresh.end());
  out.timing_ms["detect"] = elapsedMs(t);

  const float inv_scale = scale > 0.f ? 1.f / scale : 0.f;
  out.points.reserve(m.next_tracks.size());
  for (const Track& tr : m.next_tracks) {
    TrackedPoint p;
    p.id = tr.id;
    p.uv = tr.uv;
    p.age = tr.age;
    const int x = std::clamp(common::roundHalfAway(tr.uv.x()), 0, gray.cols - 1);
    const int y = std::clamp(common::roundHalfAway(tr.uv.y()), 0, gray.rows - 1);
    p.curvature = m.kappa.ptr<float>(y)[x] * inv_scale;
    p.intensity = gray.ptr<std::uint8_t>(y)[x];
    out.points.push_back(p);
  }

  std::swap(m.tracks, m.next_tracks);
  std::swap(m.prev_kappa, m.kappa);
  std::swap(m.prev_smooth, m.smooth);
  std::swap(m.prev_small, m.small);
  m.prev_scale = scale;
  m.has_prev = true;
  out.timing_ms["total"] = elapsedMs(t_all);
  return out;
}

}  // namespace vitamin_e::tracking
