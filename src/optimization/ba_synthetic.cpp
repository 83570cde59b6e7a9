#include "vitamin_e/optimization/ba_synthetic.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

#include "vitamin_e/geometry/lie.h"

namespace vitamin_e {
namespace optimization {

void SyntheticBaConfig::validate() const {
  if (num_cameras < 2) throw std::invalid_argument("num_cameras must be >= 2");
  if (num_points < 1) throw std::invalid_argument("num_points must be >= 1");
  if (!(K.fx > 0.0 && K.fy > 0.0)) throw std::invalid_argument("fx/fy must be > 0");
  if (width < 16 || height < 16) throw std::invalid_argument("width/height must be >= 16");
  if (!(min_depth > 0.0 && max_depth >= min_depth)) throw std::invalid_argument("min_depth/max_depth invalid");
  if (min_track < 2 || max_track < min_track) throw std::invalid_argument("min_track/max_track invalid");
  if (!(noise_px >= 0.0)) throw std::invalid_argument("noise_px must be >= 0");
  if (!(outlier_ratio >= 0.0 && outlier_ratio <= 1.0)) throw std::invalid_argument("outlier_ratio must be in [0,1]");
  if (!(outlier_max_px >= outlier_min_px)) throw std::invalid_argument("outlier_min_px/outlier_max_px invalid");
}

SyntheticBa makeSyntheticBa(const SyntheticBaConfig& cfg) {
  cfg.validate();
  std::mt19937 rng(cfg.seed);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  std::normal_distribution<double> gauss(0.0, 1.0);
  SyntheticBa out;
  BaProblem& P = out.truth;
  P.K = cfg.K;
  const int N = cfg.num_cameras;
  P.cameras.resize(N);
  for (int k = 0; k < N; ++k) {
    const double s = k * cfg.step_m;
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.translation() = Eigen::Vector3d(s, 0.3 * std::sin(0.8 * s), 0.5 * s);
    T.linear() = geometry::expSO3(Eigen::Vector3d(0.05 * std::sin(0.5 * s), 0.1 * std::sin(0.3 * s), 0.02 * s));
    P.cameras[k].T_w_c = T;
  }
  const double margin = 0.05;
  for (int i = 0; i < cfg.num_points; ++i) {
    for (int attempt = 0; attempt < 100; ++attempt) {
      const int max_len = std::min(cfg.max_track, N);
      const int len =
          cfg.min_track + static_cast<int>(uni(rng) * (max_len - cfg.min_track + 1)) % (max_len - cfg.min_track + 1);
      const int start = -(len - 1) + static_cast<int>(uni(rng) * (N + len - 1)) % (N + len - 1);
      const int first = std::max(0, start), last = std::min(N - 1, start + len - 1);
      if (last - first < 1) continue;
      const int ref = (first + last) / 2;
      const double u = cfg.width * (margin + (1 - 2 * margin) * uni(rng));
      const double v = cfg.height * (margin + (1 - 2 * margin) * uni(rng));
      const double z = cfg.min_depth + (cfg.max_depth - cfg.min_depth) * uni(rng);
      const Eigen::Vector3d p_c = cfg.K.ray(Eigen::Vector2d(u, v)) * z;
      const Eigen::Vector3d p_w = P.cameras[ref].T_w_c * p_c;
      std::vector<BaObservation> obs;
      for (int k = first; k <= last; ++k) {
        const Eigen::Vector3d q = P.cameras[k].T_w_c.inverse() * p_w;
        if (q.z() < 0.1) continue;
        const Eigen::Vector2d uv = cfg.K.projectPoint(q);
        if (uv.x() < 0 || uv.y() < 0 || uv.x() >= cfg.width || uv.y() >= cfg.height) continue;
        obs.push_back({k, static_cast<int>(P.points.size()), uv});
      }
      if (obs.size() < 2) continue;
      BaPoint bp;
      bp.p_w = p_w;
      P.points.push_back(bp);
      out.first_camera.push_back(obs.front().camera);
      out.last_camera.push_back(obs.back().camera);
      P.observations.insert(P.observations.end(), obs.begin(), obs.end());
      break;
    }
  }
  out.noisy = P;
  out.outlier.assign(P.observations.size(), false);
  for (size_t k = 0; k < P.observations.size(); ++k) {
    Eigen::Vector2d& uv = out.noisy.observations[k].uv;
    uv += cfg.noise_px * Eigen::Vector2d(gauss(rng), gauss(rng));
    if (uni(rng) < cfg.outlier_ratio) {
      const double a = 2.0 * M_PI * uni(rng);
      const double m = cfg.outlier_min_px + (cfg.outlier_max_px - cfg.outlier_min_px) * uni(rng);
      uv += m * Eigen::Vector2d(std::cos(a), std::sin(a));
      out.outlier[k] = true;
    }
  }
  return out;
}

void perturbBaProblem(BaProblem* problem, double rot_deg, double trans_m, double point_m, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  for (BaCamera& c : problem->cameras) {
    if (c.fixed) continue;
    const Eigen::Vector3d w(gauss(rng), gauss(rng), gauss(rng));
    const Eigen::Vector3d dt(gauss(rng), gauss(rng), gauss(rng));
    Eigen::Isometry3d D = Eigen::Isometry3d::Identity();
    D.linear() = geometry::expSO3(w * (rot_deg * M_PI / 180.0));
    D.translation() = dt * trans_m;
    c.T_w_c = c.T_w_c * D;
  }
  for (BaPoint& p : problem->points) {
    if (p.fixed) continue;
    p.p_w += point_m * Eigen::Vector3d(gauss(rng), gauss(rng), gauss(rng));
  }
}

double cameraPositionRmse(const BaProblem& estimate, const BaProblem& truth, const std::vector<bool>& mask) {
  double sum = 0.0;
  int n = 0;
  for (size_t c = 0; c < estimate.cameras.size() && c < truth.cameras.size(); ++c) {
    if (!mask.empty() && !mask[c]) continue;
    sum += (estimate.cameras[c].T_w_c.translation() - truth.cameras[c].T_w_c.translation()).squaredNorm();
    ++n;
  }
  return n > 0 ? std::sqrt(sum / n) : 0.0;
}

}  // namespace optimization
}  // namespace vitamin_e
