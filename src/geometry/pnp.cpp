#include "vitamin_e/geometry/pnp.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <stdexcept>
#include <utility>

#include "vitamin_e/geometry/lie.h"
#include "vitamin_e/geometry/projection.h"

namespace vitamin_e {
namespace geometry {

void PnpConfig::validate() const {
  if (!(focal_px > 0.0)) throw std::invalid_argument("focal_px must be > 0");
  if (!(ransac_threshold_px > 0.0)) throw std::invalid_argument("ransac_threshold_px must be > 0");
  if (!(confidence > 0.0 && confidence < 1.0)) throw std::invalid_argument("confidence must be in (0, 1)");
  if (max_iterations < 1) throw std::invalid_argument("max_iterations must be >= 1");
  if (min_inliers < 4) throw std::invalid_argument("min_inliers must be >= 4");
  if (!(min_inlier_ratio >= 0.0 && min_inlier_ratio <= 1.0))
    throw std::invalid_argument("min_inlier_ratio must be in [0, 1]");
  if (!(robust_sigma_px > 0.0)) throw std::invalid_argument("robust_sigma_px must be > 0");
  if (refine_iterations < 0) throw std::invalid_argument("refine_iterations must be >= 0");
  if (!(guess_min_inlier_ratio >= 0.0 && guess_min_inlier_ratio <= 1.0))
    throw std::invalid_argument("guess_min_inlier_ratio must be in [0, 1]");
}

namespace {

// Classifies inliers by reprojection error (pixels) under T_w_c; returns their count.
int classify(const std::vector<Eigen::Vector3d>& p_w, const std::vector<Eigen::Vector2d>& xy,
             const Eigen::Isometry3d& T_w_c, double focal_px, double thr_px, std::vector<bool>* inliers) {
  const Eigen::Isometry3d T_c_w = T_w_c.inverse();
  inliers->assign(p_w.size(), false);
  int n = 0;
  for (size_t i = 0; i < p_w.size(); ++i) {
    const Eigen::Vector3d pc = T_c_w * p_w[i];
    if (pc.z() <= 1e-9) continue;
    const double e = (xy[i] - pc.head<2>() / pc.z()).norm() * focal_px;
    if (e < thr_px) {
      (*inliers)[i] = true;
      ++n;
    }
  }
  return n;
}

}  // namespace

double refinePoseGemanMcClure(const std::vector<Eigen::Vector3d>& p_w, const std::vector<Eigen::Vector2d>& xy,
                              const std::vector<bool>& mask, double focal_px, double sigma_px, int iterations,
                              Eigen::Isometry3d* T_w_c) {
  const GemanMcClure kernel(sigma_px);
  const camera::Pinhole K{focal_px, focal_px, 0.0, 0.0};  // residuals in pixels: focal_px * normalized
  // One pass gives a pose's cost and its normal equations: the cost decides
  // whether a step is taken, and a taken step's equations are the next
  // iteration's, so every point is projected once per pose tried.
  struct Linearization {
    double cost = 0.0;
    Matrix6d H = Matrix6d::Zero();
    Vector6d g = Vector6d::Zero();
  };
  auto linearize = [&](const Eigen::Isometry3d& T, Linearization* lin) {
    const Eigen::Isometry3d T_c_w = T.inverse();
    lin->cost = 0.0;
    lin->H.setZero();
    lin->g.setZero();
    for (size_t i = 0; i < p_w.size(); ++i) {
      if (!mask.empty() && !mask[i]) continue;
      const Eigen::Vector3d pc = T_c_w * p_w[i];
      if (pc.z() <= 1e-9) {
        lin->cost += kernel.sigma2;  // behind the camera: saturated
        continue;
      }
      const Eigen::Vector2d r = focal_px * xy[i] - K.projectPoint(pc);
      const double s = r.squaredNorm();
      lin->cost += kernel.rho(s);
      const double w = kernel.weight(s);
      Matrix26d J;
      reprojectionJacobians(K, pc, T.linear(), &J, nullptr);
      lin->H.noalias() += w * J.transpose() * J;
      lin->g.noalias() += w * J.transpose() * r;
    }
  };
  Linearization at;
  linearize(*T_w_c, &at);
  Linearization trial;
  double lambda = 1e-6;
  for (int it = 0; it < iterations; ++it) {
    bool improved = false;
    for (int attempt = 0; attempt < 6 && !improved; ++attempt) {
      Matrix6d Hd = at.H;
      Hd.diagonal() *= (1.0 + lambda);
      const Vector6d delta = Hd.ldlt().solve(-at.g);
      if (!delta.allFinite()) break;
      const Eigen::Isometry3d T_new = normalizedIsometry(*T_w_c * expSE3(delta));
      linearize(T_new, &trial);
      if (trial.cost <= at.cost) {
        const double rel = (at.cost - trial.cost) / std::max(at.cost, 1e-300);
        *T_w_c = T_new;
        std::swap(at, trial);
        lambda = std::max(lambda * 0.1, 1e-9);
        improved = true;
        if (rel < 1e-10 || delta.norm() < 1e-12) return at.cost;
      } else {
        lambda *= 10.0;
      }
    }
    if (!improved) break;
  }
  return at.cost;
}

PnpResult solvePnpRansac(const std::vector<Eigen::Vector3d>& p_w, const std::vector<Eigen::Vector2d>& xy,
                         const PnpConfig& config, const Eigen::Isometry3d* T_w_c_guess) {
  config.validate();
  PnpResult res;
  const int n = static_cast<int>(p_w.size());
  if (static_cast<int>(xy.size()) != n) throw std::invalid_argument("solvePnpRansac: p_w and xy differ in size");
  if (n < std::max(4, config.min_inliers)) {
    res.reason = "too few correspondences";
    res.inliers.assign(n, false);
    return res;
  }
  const int need = std::max(config.min_inliers, static_cast<int>(std::ceil(config.min_inlier_ratio * n)));

  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  bool have_pose = false;
  if (T_w_c_guess) {
    std::vector<bool> in;
    // Looser gate for the guess (a motion model is a few pixels off), then refine.
    const int n_in = classify(p_w, xy, *T_w_c_guess, config.focal_px, 4.0 * config.ransac_threshold_px, &in);
    if (n_in >= need && n_in >= config.guess_min_inlier_ratio * n) {
      T = *T_w_c_guess;
      refinePoseGemanMcClure(p_w, xy, in, config.focal_px, config.robust_sigma_px, config.refine_iterations, &T);
      const int n_after = classify(p_w, xy, T, config.focal_px, config.ransac_threshold_px, &in);
      if (n_after >= need && n_after >= config.guess_min_inlier_ratio * n) {
        have_pose = true;
        res.used_guess = true;
      }
    }
  }
  if (!have_pose) {
    std::vector<cv::Point3d> obj(n);
    std::vector<cv::Point2d> img(n);
    for (int i = 0; i < n; ++i) {
      obj[i] = cv::Point3d(p_w[i].x(), p_w[i].y(), p_w[i].z());
      img[i] = cv::Point2d(xy[i].x(), xy[i].y());
    }
    cv::Mat rvec, tvec;
    std::vector<int> idx;
    const bool found = cv::solvePnPRansac(
        obj, img, cv::Mat::eye(3, 3, CV_64F), cv::noArray(), rvec, tvec, false, config.max_iterations,
        static_cast<float>(config.ransac_threshold_px / config.focal_px), config.confidence, idx, cv::SOLVEPNP_AP3P);
    if (!found || static_cast<int>(idx.size()) < 4) {
      res.reason = "RANSAC found no pose";
      res.inliers.assign(n, false);
      return res;
    }
    cv::Mat Rcv;
    cv::Rodrigues(rvec, Rcv);
    Eigen::Matrix3d R_c_w;
    Eigen::Vector3d t_c_w;
    cv::cv2eigen(Rcv, R_c_w);
    cv::cv2eigen(tvec, t_c_w);
    Eigen::Isometry3d T_c_w = Eigen::Isometry3d::Identity();
    T_c_w.linear() = R_c_w;
    T_c_w.translation() = t_c_w;
    T = normalizedIsometry(T_c_w.inverse());
    std::vector<bool> in(n, false);
    for (int i : idx) in[i] = true;
    refinePoseGemanMcClure(p_w, xy, in, config.focal_px, config.robust_sigma_px, config.refine_iterations, &T);
  }
  // Final pass: re-classify, refine on the final inlier set, classify again.
  std::vector<bool> in;
  classify(p_w, xy, T, config.focal_px, config.ransac_threshold_px, &in);
  refinePoseGemanMcClure(p_w, xy, in, config.focal_px, config.robust_sigma_px, config.refine_iterations, &T);
  res.num_inliers = classify(p_w, xy, T, config.focal_px, config.ransac_threshold_px, &res.inliers);
  res.T_w_c = T;
  if (res.num_inliers < need) {
    res.reason = "too few inliers";
    return res;
  }
  res.ok = true;
  return res;
}

}  // namespace geometry
}  // namespace vitamin_e
