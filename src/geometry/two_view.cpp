#include "vitamin_e/geometry/two_view.h"

#include <Eigen/Dense>
#include <Eigen/SVD>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <stdexcept>

#include "vitamin_e/geometry/lie.h"
#include "vitamin_e/geometry/projection.h"
#include "vitamin_e/geometry/triangulation.h"

#include "two_view_detail.h"

namespace vitamin_e {
namespace geometry {

void TwoViewConfig::validate() const {
  if (!(ransac_threshold_px > 0.0)) throw std::invalid_argument("ransac_threshold_px must be > 0");
  if (!(focal_px > 0.0)) throw std::invalid_argument("focal_px must be > 0");
  if (!(min_parallax_deg >= 0.0)) throw std::invalid_argument("min_parallax_deg must be >= 0");
  if (!(min_inlier_ratio >= 0.0 && min_inlier_ratio <= 1.0))
    throw std::invalid_argument("min_inlier_ratio must be in [0, 1]");
  if (min_points < 5) throw std::invalid_argument("min_points must be >= 5");
  if (!(confidence > 0.0 && confidence < 1.0)) throw std::invalid_argument("confidence must be in (0, 1)");
  if (max_iterations < 1) throw std::invalid_argument("max_iterations must be >= 1");
  if (!(max_reproj_error_px > 0.0)) throw std::invalid_argument("max_reproj_error_px must be > 0");
  if (!(point_min_parallax_deg >= 0.0)) throw std::invalid_argument("point_min_parallax_deg must be >= 0");
  if (!(rotation_only_max_ratio > 0.0)) throw std::invalid_argument("rotation_only_max_ratio must be > 0");
  if (!(planar_min_ratio > 0.0)) throw std::invalid_argument("planar_min_ratio must be > 0");
  if (!(planar_distinct_deg > 0.0 && planar_distinct_deg < 180.0))
    throw std::invalid_argument("planar_distinct_deg must be in (0, 180)");
  if (!(ambiguous_rival_ratio > 0.0)) throw std::invalid_argument("ambiguous_rival_ratio must be > 0");
  if (!(homography_min_gain >= 0.0)) throw std::invalid_argument("homography_min_gain must be >= 0");
  if (!(min_valid_ratio >= 0.0 && min_valid_ratio <= 1.0))
    throw std::invalid_argument("min_valid_ratio must be in [0, 1]");
}

namespace detail {

int poseFromEssential(const Eigen::Matrix3d& E, const std::vector<Eigen::Vector2d>& xy0,
                      const std::vector<Eigen::Vector2d>& xy1, const std::vector<bool>& mask, double max_depth,
                      Eigen::Matrix3d* R, Eigen::Vector3d* t) {
  if (!E.allFinite()) return 0;
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(E, Eigen::ComputeFullU | Eigen::ComputeFullV);
  if (!(svd.singularValues()(0) > 0.0)) return 0;
  Eigen::Matrix3d U = svd.matrixU(), V = svd.matrixV();
  if (U.determinant() < 0.0) U = -U;
  if (V.determinant() < 0.0) V = -V;
  Eigen::Matrix3d W;
  W << 0.0, -1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0;
  const Eigen::Matrix3d Rs[2] = {U * W * V.transpose(), U * W.transpose() * V.transpose()};
  const Eigen::Vector3d t0 = U.col(2);
  // good[2 r + s]: rotation r, translation +t0 (s = 0) or -t0 (s = 1). Flipping t flips both
  // least-squares depths, so one solve per rotation serves both signs.
  std::array<int, 4> good{};
  const size_t n = std::min(xy0.size(), xy1.size());
  for (size_t i = 0; i < n; ++i) {
    if (i < mask.size() && !mask[i]) continue;
    const Eigen::Vector3d b = xy1[i].homogeneous();
    for (size_t r = 0; r < 2; ++r) {
      const Eigen::Vector3d a = Rs[r] * xy0[i].homogeneous();
      // z0 a - z1 b = -t0 in least squares.
      const double aa = a.squaredNorm(), ab = a.dot(b), bb = b.squaredNorm();
      const double at = a.dot(t0), bt = b.dot(t0);
      const double det = aa * bb - ab * ab;
      if (!(det > 1e-15 * aa * bb)) continue;  // parallel rays: no depth
      const double z0 = (-at * bb + bt * ab) / det;
      const double z1 = (z0 * a + t0).z();  // depth in camera 1 of the point at depth z0 (x0's z is 1)
      if (z0 > 0.0 && z1 > 0.0 && z0 < max_depth && z1 < max_depth) ++good[2 * r];
      if (z0 < 0.0 && z1 < 0.0 && -z0 < max_depth && -z1 < max_depth) ++good[2 * r + 1];
    }
  }
  const size_t best = static_cast<size_t>(std::max_element(good.begin(), good.end()) - good.begin());
  if (good[best] == 0) return 0;
  *R = Rs[best / 2];
  *t = best % 2 == 0 ? t0 : Eigen::Vector3d(-t0);
  return good[best];
}

}  // namespace detail

Eigen::Matrix3d fitRotationOnly(const std::vector<Eigen::Vector2d>& xy0, const std::vector<Eigen::Vector2d>& xy1,
                                const std::vector<bool>& mask) {
  Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
  for (size_t i = 0; i < xy0.size(); ++i) {
    if (!mask.empty() && !mask[i]) continue;
    const Eigen::Vector3d b0 = xy0[i].homogeneous().normalized();
    const Eigen::Vector3d b1 = xy1[i].homogeneous().normalized();
    C.noalias() += b1 * b0.transpose();
  }
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(C, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
  if ((svd.matrixU() * svd.matrixV().transpose()).determinant() < 0.0) D(2, 2) = -1.0;
  return svd.matrixU() * D * svd.matrixV().transpose();
}

namespace {

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  const size_t m = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(m), v.end());
  return v[m];
}

// Refines (R, t) with |t| = 1 (5 DoF: R <- R expSO3(w), t <- normalize(t + B d)) on the Sampson
// distance with Geman-McClure IRLS. The denominator is frozen within an iteration, so the
// Jacobian of the epipolar residual x1^T [t]x R x0 is analytic (detail::sampsonJacobian).
void refineRelativePose(const std::vector<Eigen::Vector2d>& xy0, const std::vector<Eigen::Vector2d>& xy1,
                        const std::vector<bool>& mask, double focal, double sigma_px, int iterations,
                        Eigen::Matrix3d* R, Eigen::Vector3d* t) {
  const GemanMcClure kernel(sigma_px);
  auto cost_of = [&](const Eigen::Matrix3d& Rc, const Eigen::Vector3d& tc) {
    const Eigen::Matrix3d E = skew(tc) * Rc;
    double c = 0.0, d;
    for (size_t i = 0; i < xy0.size(); ++i)
      if (mask[i])
        c += kernel.rho(std::pow(focal * detail::sampson(E, xy0[i].homogeneous(), xy1[i].homogeneous(), &d), 2));
    return c;
  };
  double cost = cost_of(*R, *t);
  double lambda = 1e-6;
  for (int it = 0; it < iterations; ++it) {
    const Eigen::Matrix3d E = skew(*t) * *R;
    const Eigen::Matrix<double, 3, 2> B = detail::tangentBasis(*t);
    Eigen::Matrix<double, 5, 5> H = Eigen::Matrix<double, 5, 5>::Zero();
    Eigen::Matrix<double, 5, 1> g = Eigen::Matrix<double, 5, 1>::Zero();
    for (size_t i = 0; i < xy0.size(); ++i) {
      if (!mask[i]) continue;
      const Eigen::Vector3d x0 = xy0[i].homogeneous(), x1 = xy1[i].homogeneous();
      double d;
      const double r = focal * detail::sampson(E, x0, x1, &d);
      const double s = focal / d;
      const Eigen::Matrix<double, 1, 5> J = detail::sampsonJacobian(*R, *t, B, x0, x1, s);
      const double w = kernel.weight(r * r);
      H.noalias() += w * J.transpose() * J;
      g.noalias() += w * J.transpose() * r;
    }
    bool improved = false;
    for (int attempt = 0; attempt < 6 && !improved; ++attempt) {
      Eigen::Matrix<double, 5, 5> Hd = H;
      Hd.diagonal() *= 1.0 + lambda;
      const Eigen::Matrix<double, 5, 1> delta = Hd.ldlt().solve(-g);
      if (!delta.allFinite()) return;
      const Eigen::Matrix3d R_new = *R * expSO3(delta.head<3>());
      const Eigen::Vector3d t_new = (*t + B * delta.tail<2>()).normalized();
      const double c_new = cost_of(R_new, t_new);
      if (c_new <= cost) {
        improved = true;
        const double rel = (cost - c_new) / std::max(cost, 1e-300);
        *R = R_new;
        *t = t_new;
        cost = c_new;
        lambda = std::max(1e-9, lambda * 0.1);
        if (rel < 1e-10) return;
      } else {
        lambda *= 10.0;
      }
    }
    if (!improved) return;
  }
}


struct Motion {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::UnitX();  // unit norm
};

struct Reconstruction {
  Motion motion;
  std::vector<bool> valid;
  std::vector<Eigen::Vector3d> points;  // camera 0, |t| = 1
  std::vector<double> parallax, depth;  // of the valid points
  int num_valid = 0;
};

// Triangulates every selected correspondence under a motion (camera 0 at the origin).
Reconstruction triangulateInliers(const Motion& m, const std::vector<Eigen::Vector2d>& xy0,
                                  const std::vector<Eigen::Vector2d>& xy1, const std::vector<bool>& mask,
                                  const TwoViewConfig& config) {
  Reconstruction rec;
  rec.motion = m;
  rec.valid.assign(xy0.size(), false);
  rec.points.assign(xy0.size(), Eigen::Vector3d::Zero());
  Eigen::Isometry3d T_c1_c0 = Eigen::Isometry3d::Identity();
  T_c1_c0.linear() = m.R;
  T_c1_c0.translation() = m.t;
  const std::vector<Eigen::Isometry3d> T_w_c = {Eigen::Isometry3d::Identity(), T_c1_c0.inverse()};
  TriangulationConfig tc;
  tc.focal_px = config.focal_px;
  tc.min_parallax_deg = config.point_min_parallax_deg;
  tc.max_reproj_error_px = config.max_reproj_error_px;
  tc.gn_iterations = 5;
  for (size_t i = 0; i < xy0.size(); ++i) {
    if (!mask[i]) continue;
    const TriangulationResult tr = triangulatePoint(T_w_c, {xy0[i], xy1[i]}, tc);
    if (!tr.ok) continue;
    rec.valid[i] = true;
    rec.points[i] = tr.p_w;
    rec.parallax.push_back(tr.parallax_deg);
    rec.depth.push_back(tr.p_w.z());
  }
  rec.num_valid = static_cast<int>(rec.depth.size());
  return rec;
}

// Homography x1 ~ H x0 (normalized coordinates) by RANSAC, then least squares on its inliers.
bool fitHomography(const std::vector<Eigen::Vector2d>& xy0, const std::vector<Eigen::Vector2d>& xy1, double thr,
                   Eigen::Matrix3d* H) {
  if (xy0.size() < 8) return false;
  std::vector<cv::Point2d> p0(xy0.size()), p1(xy1.size());
  for (size_t i = 0; i < xy0.size(); ++i) {
    p0[i] = cv::Point2d(xy0[i].x(), xy0[i].y());
    p1[i] = cv::Point2d(xy1[i].x(), xy1[i].y());
  }
  const cv::Mat Hcv = cv::findHomography(p0, p1, cv::RANSAC, 2.0 * thr);
  if (Hcv.empty()) return false;
  cv::cv2eigen(Hcv, *H);
  return H->allFinite();
}

// The motions of a calibrated homography H = R + t n^T (plane n^T X = 1 in camera 0): up
// to four (R, t) with |t| = 1; cheirality is left to the caller.
std::vector<Motion> decomposeHomography(const Eigen::Matrix3d& H) {
  std::vector<cv::Mat> Rs, ts, ns;
  cv::Mat Hcv;
  cv::eigen2cv(H, Hcv);
  cv::decomposeHomographyMat(Hcv, cv::Mat::eye(3, 3, CV_64F), Rs, ts, ns);
  std::vector<Motion> out;
  for (size_t k = 0; k < Rs.size(); ++k) {
    Motion m;
    cv::cv2eigen(Rs[k], m.R);
    Eigen::Vector3d tk;
    cv::cv2eigen(ts[k], tk);
    if (!m.R.allFinite() || !tk.allFinite() || tk.norm() < 1e-12) continue;
    m.t = tk.normalized();
    out.push_back(m);
  }
  return out;
}

}  // namespace

TwoViewResult initializeTwoView(const std::vector<Eigen::Vector2d>& xy0, const std::vector<Eigen::Vector2d>& xy1,
                                const TwoViewConfig& config) {
  config.validate();
  TwoViewResult res;
  const int n = static_cast<int>(xy0.size());
  if (static_cast<int>(xy1.size()) != n) throw std::invalid_argument("initializeTwoView: xy0 and xy1 differ in size");
  res.points_c0.assign(n, Eigen::Vector3d::Zero());
  res.valid.assign(n, false);
  if (n < config.min_points) {
    res.reason = "too few correspondences";
    return res;
  }

  std::vector<cv::Point2d> p0(n), p1(n);
  for (int i = 0; i < n; ++i) {
    p0[i] = cv::Point2d(xy0[i].x(), xy0[i].y());
    p1[i] = cv::Point2d(xy1[i].x(), xy1[i].y());
  }
  const cv::Mat K = cv::Mat::eye(3, 3, CV_64F);
  const double thr = config.ransac_threshold_px / config.focal_px;
  cv::Mat mask;
  cv::Mat E = cv::findEssentialMat(p0, p1, K, cv::RANSAC, config.confidence, thr, config.max_iterations, mask);
  if (E.empty() || E.rows != 3 || E.cols != 3) {  // several solutions stack as 3k x 3: take the first
    if (E.rows < 3) {
      res.reason = "essential matrix estimation failed";
      return res;
    }
  }
  Eigen::Matrix3d E_eig;
  cv::cv2eigen(cv::Mat(E.rowRange(0, 3)), E_eig);
  std::vector<bool> ransac_in(n, true);
  if (mask.total() == static_cast<size_t>(n)) {
    for (int i = 0; i < n; ++i) ransac_in[i] = mask.at<std::uint8_t>(i) != 0;
  }
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::UnitZ();
  // 50 |t|: cv::recoverPose's distance threshold for points at infinity.
  const int n_good = detail::poseFromEssential(E_eig, xy0, xy1, ransac_in, 50.0, &R, &t);
  if (n_good < config.min_points) {
    res.reason = "too few essential-matrix inliers";
    return res;
  }
  std::vector<bool> e_in(n, false);
  // The RANSAC model comes from a minimal sample and its inlier set is biased towards it:
  // alternate re-selecting the correspondences (Sampson distance < 2 thresholds) under the
  // current model and polishing the model on them.
  for (int round = 0; round < 3; ++round) {
    const Eigen::Matrix3d Ecur = skew(t) * R;
    std::vector<bool> sel(n, false);
    for (int i = 0; i < n; ++i) {
      double d;
      sel[i] = std::abs(detail::sampson(Ecur, xy0[i].homogeneous(), xy1[i].homogeneous(), &d)) * config.focal_px <
               2.0 * config.ransac_threshold_px;
    }
    refineRelativePose(xy0, xy1, sel, config.focal_px, config.ransac_threshold_px, 10, &R, &t);
    if (round == 2) e_in = sel;
  }
  const int n_e = static_cast<int>(std::count(e_in.begin(), e_in.end(), true));
  res.num_essential_inliers = n_e;
  if (n_e < config.min_points || n_e < config.min_inlier_ratio * n) {
    res.reason = "too few essential-matrix inliers";
    return res;
  }

  // Degeneracy: does a rotation-only model explain the same correspondences?
  {
    const Eigen::Matrix3d R_rot = fitRotationOnly(xy0, xy1, e_in);
    int n_rot = 0;
    for (int i = 0; i < n; ++i) {
      if (!e_in[i]) continue;
      const Eigen::Vector3d q = R_rot * xy0[i].homogeneous();
      if (q.z() > 0.0 && (xy1[i] - q.head<2>() / q.z()).norm() * config.focal_px < 2.0 * config.ransac_threshold_px)
        ++n_rot;
    }
    res.num_rotation_only_inliers = n_rot;
    if (n_rot >= config.rotation_only_max_ratio * n_e) {
      res.reason = "degenerate: a rotation-only model explains the motion (no translation)";
      return res;
    }
  }

  // The motion candidates. For a scene that is (nearly) one plane, the essential matrix is
  // not unique: the plane's homography has two physically different decompositions, and the
  // five-point RANSAC returns either of them at random. The false one ("twisted" motion,
  // roughly along the plane normal instead of across it) explains every correspondence
  // just as well, so inlier counts cannot tell them apart; only cheirality can: under it,
  // part of the points land behind a camera. When a homography explains nearly all the
  // essential inliers, its decompositions are therefore added as candidates, and the
  // candidate that triangulates the most points in front of both cameras wins.
  std::vector<Motion> candidates;
  candidates.push_back({R, t});
  {
    std::vector<Eigen::Vector2d> in0, in1;
    for (int i = 0; i < n; ++i) {
      if (!e_in[i]) continue;
      in0.push_back(xy0[i]);
      in1.push_back(xy1[i]);
    }
    Eigen::Matrix3d H;
    if (config.planar_min_ratio <= 1.0 && fitHomography(in0, in1, thr, &H)) {
      int n_h = 0;
      for (size_t i = 0; i < in0.size(); ++i) {
        const Eigen::Vector3d q = H * in0[i].homogeneous();
        if (q.z() > 0.0 && (in1[i] - q.head<2>() / q.z()).norm() * config.focal_px < 2.0 * config.ransac_threshold_px)
          ++n_h;
      }
      res.num_homography_inliers = n_h;
      if (n_h >= config.planar_min_ratio * n_e) {
        res.planar = true;
        for (const Motion& m : decomposeHomography(H)) candidates.push_back(m);
      }
    }
  }
  int best_index = -1;
  std::vector<Reconstruction> recs;
  for (size_t c = 0; c < candidates.size(); ++c) {
    recs.push_back(triangulateInliers(candidates[c], xy0, xy1, e_in, config));
    if (best_index < 0 || recs.back().num_valid > recs[best_index].num_valid) best_index = static_cast<int>(c);
  }
  // At small parallax a homography fits any scene, and its motions can edge out the
  // essential one by a few points of noise while being the wrong motion. The twisted
  // motion loses about half of the points, so a homography motion must beat the
  // essential one clearly.
  if (best_index > 0 && recs[best_index].num_valid < (1.0 + config.homography_min_gain) * recs[0].num_valid) {
    best_index = 0;
  }
  if (res.planar && best_index > 0) {
    // A homography motion won: polish it on the epipolar error like the essential one, and
    // keep the polished motion only if it does not lose points.
    Motion polished = candidates[best_index];
    refineRelativePose(xy0, xy1, e_in, config.focal_px, config.ransac_threshold_px, 10, &polished.R, &polished.t);
    Reconstruction rp = triangulateInliers(polished, xy0, xy1, e_in, config);
    if (rp.num_valid >= recs[best_index].num_valid) recs[best_index] = std::move(rp);
  }
  const Reconstruction& best = recs[best_index];
  res.used_homography = best_index > 0;
  // A rival: the most points triangulated by a candidate whose translation points elsewhere.
  for (size_t c = 0; c < recs.size(); ++c) {
    const double cos_dir = recs[c].motion.t.normalized().dot(best.motion.t.normalized());
    if (cos_dir < std::cos(config.planar_distinct_deg * M_PI / 180.0))
      res.num_rival_inliers = std::max(res.num_rival_inliers, recs[c].num_valid);
  }
  R = best.motion.R;
  t = best.motion.t;
  Eigen::Isometry3d T_c1_c0 = Eigen::Isometry3d::Identity();
  T_c1_c0.linear() = R;
  T_c1_c0.translation() = t;
  res.valid = best.valid;
  res.points_c0 = best.points;
  const std::vector<double>& depth = best.depth;
  res.num_inliers = best.num_valid;
  res.median_parallax_deg = median(best.parallax);
  if (res.num_inliers < config.min_points) {
    res.reason = "too few valid triangulated points";
    return res;
  }
  if (res.num_inliers < config.min_valid_ratio * n_e) {
    res.reason = "degenerate: only " + std::to_string(res.num_inliers) + " of " + std::to_string(n_e) +
                 " essential inliers triangulate in front of both cameras";
    return res;
  }
  res.ambiguous = res.num_rival_inliers >= config.ambiguous_rival_ratio * res.num_inliers;
  if (res.ambiguous && config.refuse_ambiguous) {
    res.reason = "ambiguous: planar scene, two different motions explain the views (" +
                 std::to_string(res.num_inliers) + " vs " + std::to_string(res.num_rival_inliers) + " points)";
    return res;
  }
  if (res.median_parallax_deg < config.min_parallax_deg) {
    res.reason = "degenerate: median parallax below min_parallax_deg";
    return res;
  }
  // Scale: median depth of the valid points in camera 0 becomes 1.
  const double s = 1.0 / median(depth);
  for (int i = 0; i < n; ++i)
    if (res.valid[i]) res.points_c0[i] *= s;
  T_c1_c0.translation() *= s;
  res.T_c1_c0 = T_c1_c0;
  res.ok = true;
  return res;
}

}  // namespace geometry
}  // namespace vitamin_e
