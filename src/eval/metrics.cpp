#include "vitamin_e/eval/metrics.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>

namespace vitamin_e::eval {
namespace {

std::string span(const Trajectory& t) {
  if (t.empty()) return "no poses";
  char buf[128];
  std::snprintf(buf, sizeof(buf), "%zu poses, t = %.3f .. %.3f s", t.size(), t.front().t, t.back().t);
  return buf;
}

// Translation error of the relative motion a -> b of the (scaled) estimate
// against the ground truth's.
double relativeError(const Eigen::Isometry3d& Ea, const Eigen::Isometry3d& Eb, const Eigen::Isometry3d& Ga,
                     const Eigen::Isometry3d& Gb, double scale) {
  Eigen::Isometry3d E_rel = Ea.inverse() * Eb;
  E_rel.translation() *= scale;
  const Eigen::Isometry3d G_rel = Ga.inverse() * Gb;
  return (G_rel.inverse() * E_rel).translation().norm();
}

std::string jsonNumber(double v, const ErrorStats& s) {
  if (s.count == 0 || !std::isfinite(v)) return "null";
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.6f", v);
  return buf;
}

const char* alignmentName(const EvalConfig& config) {
  return config.given_alignment ? "given" : config.align_scale ? "sim3" : "se3";
}

}  // namespace

void EvalConfig::validate() const {
  if (!(max_dt > 0.0) || !std::isfinite(max_dt)) throw std::invalid_argument("max_dt must be > 0");
  if (!(rpe_delta_s > 0.0) || !std::isfinite(rpe_delta_s)) throw std::invalid_argument("rpe_delta_s must be > 0");
  if (given_alignment && (!(given_alignment->scale > 0.0) || !std::isfinite(given_alignment->scale) ||
                          !given_alignment->R.allFinite() || !given_alignment->t.allFinite())) {
    throw std::invalid_argument("the given alignment is not a similarity transform");
  }
}

ErrorStats errorStats(const std::vector<double>& errors) {
  ErrorStats s;
  s.count = errors.size();
  if (errors.empty()) return s;
  double sum = 0.0, sum_sq = 0.0;
  for (double e : errors) {
    sum += e;
    sum_sq += e * e;
    s.max = std::max(s.max, e);
  }
  const double n = static_cast<double>(errors.size());
  s.mean = sum / n;
  s.rmse = std::sqrt(sum_sq / n);
  std::vector<double> sorted = errors;
  std::sort(sorted.begin(), sorted.end());
  const std::size_t m = sorted.size() / 2;
  s.median = sorted.size() % 2 ? sorted[m] : 0.5 * (sorted[m - 1] + sorted[m]);
  return s;
}

EvalResult evaluate(const Trajectory& estimate, const Trajectory& ground_truth, const EvalConfig& config) {
  config.validate();
  EvalResult r;
  r.estimate_poses = estimate.size();
  r.ground_truth_poses = ground_truth.size();
  r.pairs = associate(estimate, ground_truth, config.max_dt);
  r.matched = r.pairs.size();
  r.frames = config.frames > 0 ? config.frames : estimate.size();
  r.success_rate = r.frames > 0 ? static_cast<double>(r.matched) / static_cast<double>(r.frames) : 0.0;
  if (r.matched < 3) {
    throw TrajectoryError("only " + std::to_string(r.matched) + " poses associate within " +
                          std::to_string(config.max_dt) + " s (estimate: " + span(estimate) +
                          "; ground truth: " + span(ground_truth) + ")");
  }

  Eigen::Matrix3Xd src(3, r.matched), dst(3, r.matched);
  for (std::size_t k = 0; k < r.matched; ++k) {
    const auto c = static_cast<Eigen::Index>(k);
    src.col(c) = estimate[r.pairs[k].first].T_w_c.translation();
    dst.col(c) = ground_truth[r.pairs[k].second].T_w_c.translation();
  }
  if (config.given_alignment) {
    r.alignment = *config.given_alignment;
  } else {
    try {
      r.alignment = umeyamaAlignment(src, dst, config.align_scale);
    } catch (const std::invalid_argument& e) {
      throw TrajectoryError(std::string("cannot align: ") + e.what());
    }
  }

  r.errors.resize(r.matched);
  for (std::size_t k = 0; k < r.matched; ++k) {
    const auto c = static_cast<Eigen::Index>(k);
    r.errors[k] = (r.alignment.apply(Eigen::Vector3d(src.col(c))) - dst.col(c)).norm();
  }
  r.ate = errorStats(r.errors);
  for (Eigen::Index c = 1; c < dst.cols(); ++c) r.path_length_m += (dst.col(c) - dst.col(c - 1)).norm();

  r.aligned = estimate;
  for (auto& sp : r.aligned) sp.T_w_c = r.alignment.apply(sp.T_w_c);

  std::vector<double> rpe1, rpe_d;
  const double s = r.alignment.scale;
  for (std::size_t k = 0; k + 1 < r.matched; ++k) {
    const auto [ia, ga] = r.pairs[k];
    const auto [ib, gb] = r.pairs[k + 1];
    rpe1.push_back(
        relativeError(estimate[ia].T_w_c, estimate[ib].T_w_c, ground_truth[ga].T_w_c, ground_truth[gb].T_w_c, s));
  }
  std::size_t m = 0;
  for (std::size_t k = 0; k < r.matched; ++k) {
    const double t_k = ground_truth[r.pairs[k].second].t;
    m = std::max(m, k + 1);
    while (m < r.matched && ground_truth[r.pairs[m].second].t - t_k < config.rpe_delta_s - 1e-9) ++m;
    if (m >= r.matched) break;
    const auto [ia, ga] = r.pairs[k];
    const auto [ib, gb] = r.pairs[m];
    rpe_d.push_back(
        relativeError(estimate[ia].T_w_c, estimate[ib].T_w_c, ground_truth[ga].T_w_c, ground_truth[gb].T_w_c, s));
  }
  r.rpe_frame = errorStats(rpe1);
  r.rpe_delta = errorStats(rpe_d);
  return r;
}

std::string toJson(const EvalResult& r, const EvalConfig& config) {
  std::ostringstream o;
  char buf[512];
  std::snprintf(buf, sizeof(buf),
                "{\"ate_rmse_m\":%.6f,\"ate_mean_m\":%.6f,\"ate_median_m\":%.6f,\"ate_max_m\":%.6f,"
                "\"matched\":%zu,\"frames\":%zu,\"success_rate\":%.6f,\"scale\":%.6f,",
                r.ate.rmse, r.ate.mean, r.ate.median, r.ate.max, r.matched, r.frames, r.success_rate,
                r.alignment.scale);
  o << buf << "\"path_length_m\":" << jsonNumber(r.path_length_m, r.ate)
    << ",\"ate_path_percent\":" << jsonNumber(r.path_length_m > 0.0 ? 100.0 * r.ate.rmse / r.path_length_m : 0.0, r.ate)
    << ",\"rpe_trans_rmse_m\":" << jsonNumber(r.rpe_frame.rmse, r.rpe_frame)
    << ",\"rpe_delta_trans_rmse_m\":" << jsonNumber(r.rpe_delta.rmse, r.rpe_delta);
  std::snprintf(buf, sizeof(buf),
                ",\"rpe_delta_s\":%.3f,\"alignment\":\"%s\",\"estimate_poses\":%zu,\"ground_truth_poses\":%zu}",
                config.rpe_delta_s, alignmentName(config), r.estimate_poses, r.ground_truth_poses);
  o << buf;
  return o.str();
}

std::string summary(const EvalResult& r, const EvalConfig& config) {
  std::ostringstream o;
  char buf[256];
  std::snprintf(buf, sizeof(buf), "poses: estimate %zu, ground truth %zu, matched %zu (max dt %.3f s, nearest)\n",
                r.estimate_poses, r.ground_truth_poses, r.matched, config.max_dt);
  o << buf;
  std::snprintf(buf, sizeof(buf), "success rate: %.1f %% (%zu of %zu frames)\n", 100.0 * r.success_rate, r.matched,
                r.frames);
  o << buf;
  const Eigen::AngleAxisd aa(r.alignment.R);
  std::snprintf(buf, sizeof(buf), "alignment (%s): scale %.6f, rotation %.3f deg, translation [%.3f %.3f %.3f] m\n",
                config.given_alignment ? "given"
                : config.align_scale   ? "Sim(3)"
                                       : "SE(3)",
                r.alignment.scale, aa.angle() * 180.0 / M_PI, r.alignment.t.x(), r.alignment.t.y(), r.alignment.t.z());
  o << buf;
  std::snprintf(buf, sizeof(buf), "ATE [cm]: rmse %.3f  mean %.3f  median %.3f  max %.3f\n", 100.0 * r.ate.rmse,
                100.0 * r.ate.mean, 100.0 * r.ate.median, 100.0 * r.ate.max);
  o << buf;
  if (r.path_length_m > 0.0) {
    std::snprintf(buf, sizeof(buf), "ATE: %.3f %% of the %.1f m path\n", 100.0 * r.ate.rmse / r.path_length_m,
                  r.path_length_m);
    o << buf;
  }
  std::snprintf(buf, sizeof(buf), "RPE trans [cm]: 1 frame rmse %.3f (%zu pairs), %.2f s rmse %.3f (%zu pairs)\n",
                100.0 * r.rpe_frame.rmse, r.rpe_frame.count, config.rpe_delta_s, 100.0 * r.rpe_delta.rmse,
                r.rpe_delta.count);
  o << buf;
  return o.str();
}

}  // namespace vitamin_e::eval
