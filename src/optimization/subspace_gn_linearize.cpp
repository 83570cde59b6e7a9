#include <Eigen/Dense>
#include <cmath>

#include "subspace_gn_impl.h"

namespace vitamin_e {
namespace optimization {
namespace detail {

void SubspaceGn::buildStructure() {
  const int nc = static_cast<int>(P_.cameras.size());
  const int np = static_cast<int>(P_.points.size());
  cam_var_.assign(nc, -1);
  pt_var_.assign(np, -1);
  for (int c = 0; c < nc; ++c)
    if (!P_.cameras[c].fixed) {
      cam_var_[c] = static_cast<int>(cams_.size());
      cams_.push_back(c);
    }
  // Free points: not fixed and observed at least once.
  std::vector<int> count(np, 0);
  for (const BaObservation& o : P_.observations) ++count[o.point];
  for (int p = 0; p < np; ++p)
    if (!P_.points[p].fixed && count[p] > 0) {
      pt_var_[p] = static_cast<int>(pts_.size());
      pts_.push_back(p);
    }
  const int npf = static_cast<int>(pts_.size());
  const int ncf = static_cast<int>(cams_.size());
  // Point-major observation lists; slots = (free camera, free point) pairs, point-major.
  std::vector<int> per_point(npf + 1, 0);
  for (const BaObservation& o : P_.observations) {
    const int j = pt_var_[o.point];
    if (j >= 0) ++per_point[j + 1];
  }
  for (int j = 0; j < npf; ++j) per_point[j + 1] += per_point[j];
  pt_begin_ = per_point;
  pt_obs_.assign(per_point[npf], -1);
  for (size_t k = 0; k < P_.observations.size(); ++k) {
    const BaObservation& o = P_.observations[k];
    const int j = pt_var_[o.point];
    if (j >= 0) {
      pt_obs_[per_point[j]++] = static_cast<int>(k);
    } else if (cam_var_[o.camera] >= 0) {
      cam_only_obs_.push_back(static_cast<int>(k));
    }
  }
  obs_cam_.resize(pt_obs_.size());
  obs_uv_.resize(pt_obs_.size());
  for (size_t a = 0; a < pt_obs_.size(); ++a) {
    obs_cam_[a] = P_.observations[pt_obs_[a]].camera;
    obs_uv_[a] = P_.observations[pt_obs_[a]].uv;
  }
  obs_slot_.assign(pt_obs_.size(), -1);
  slot_begin_.assign(npf + 1, 0);
  std::vector<int> cam_count(ncf + 1, 0);
  for (int j = 0; j < npf; ++j) {
    slot_begin_[j] = static_cast<int>(slot_cam_.size());
    for (int a = pt_begin_[j]; a < pt_begin_[j + 1]; ++a) {
      const int ci = cam_var_[P_.observations[pt_obs_[a]].camera];
      if (ci < 0) continue;
      obs_slot_[a] = static_cast<int>(slot_cam_.size());
      slot_cam_.push_back(ci);
      slot_point_.push_back(j);
      ++cam_count[ci + 1];
    }
  }
  slot_begin_[npf] = static_cast<int>(slot_cam_.size());
  for (int i = 0; i < ncf; ++i) cam_count[i + 1] += cam_count[i];
  cam_begin_ = cam_count;
  cam_slots_.assign(slot_cam_.size(), -1);
  for (size_t s = 0; s < slot_cam_.size(); ++s) cam_slots_[cam_count[slot_cam_[s]]++] = static_cast<int>(s);

  Hcc_.resize(ncf);
  gc_.resize(ncf);
  b_.resize(ncf);
  dc_.resize(ncf);
  Hpp_.resize(npf);
  gp_.resize(npf);
  Hpp_inv_.resize(npf);
  dp_.resize(npf);
  q_.resize(npf);
  Hcp_.resize(slot_cam_.size());
  if (O_.use_schur) Y_.resize(slot_cam_.size());
  // Constant cost of the observations with nothing free.
  fixed_cost_ = 0.0;
  Eigen::Vector2d r;
  for (const BaObservation& o : P_.observations)
    if (cam_var_[o.camera] < 0 && pt_var_[o.point] < 0)
      fixed_cost_ += baResidual(P_, o, &r) ? kernel_.rho(r.squaredNorm()) : kernel_.sigma2;
}

namespace {

// H += w J^T J on the upper triangle only (H is symmetrized by the caller).
template <int N>
inline void addUpperJtJ(const Eigen::Matrix<double, 2, N>& J, double w, Eigen::Matrix<double, N, N>* H) {
  for (int c = 0; c < N; ++c) {
    const double a0 = w * J(0, c), a1 = w * J(1, c);
    for (int r = 0; r <= c; ++r) (*H)(r, c) += a0 * J(0, r) + a1 * J(1, r);
  }
}

template <int N>
inline void mirrorUpper(Eigen::Matrix<double, N, N>* H) {
  for (int c = 0; c < N; ++c)
    for (int r = c + 1; r < N; ++r) (*H)(r, c) = (*H)(c, r);
}

}  // namespace

double SubspaceGn::linearize() {
  const int ncf = freeCameras();
  const int npf = freePoints();
  cacheCameras();
  const int T = std::max(1, O_.threads);
  Hcc_t_.resize(T);
  gc_t_.resize(T);
  for (int t = 0; t < T; ++t) {
    Hcc_t_[t].assign(ncf, Matrix6d::Zero());
    gc_t_[t].assign(ncf, Vector6d::Zero());
  }
  std::vector<double> cost_t(T, 0.0);
  parallelFor(npf, T, [&](int begin, int end, int t) {
    double cost = 0.0;
    std::vector<Matrix6d>& Hcc = Hcc_t_[t];
    std::vector<Vector6d>& gc = gc_t_[t];
    for (int j = begin; j < end; ++j) {
      Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
      Eigen::Vector3d g = Eigen::Vector3d::Zero();
      const Eigen::Vector3d p = P_.points[pts_[j]].p_w;
      for (int a = pt_begin_[j]; a < pt_begin_[j + 1]; ++a) {
        const int c = obs_cam_[a];
        const Eigen::Vector3d p_c = Rt_[c] * (p - t_[c]);
        const int s = obs_slot_[a];
        if (p_c.z() <= kMinDepth) {
          cost += kernel_.sigma2;
          if (s >= 0) Hcp_[s].setZero();
          continue;
        }
        const Eigen::Vector2d r = obs_uv_[a] - K_.project(p_c);
        const double sq = r.squaredNorm();
        cost += kernel_.rho(sq);
        const double w = kernel_.weight(sq);
        const geometry::Matrix23d Jproj = K_.jacobian(p_c);
        const geometry::Matrix23d Jp = -Jproj * Rt_[c];
        addUpperJtJ<3>(Jp, w, &H);
        const Eigen::Vector2d wr = w * r;
        g.noalias() += Jp.transpose() * wr;
        if (s >= 0) {
          geometry::Matrix26d Jc;
          Jc.leftCols<3>() = Jproj;
          Jc.rightCols<3>().noalias() = -Jproj * geometry::skew(p_c);
          const int ci = slot_cam_[s];
          addUpperJtJ<6>(Jc, w, &Hcc[ci]);
          gc[ci].noalias() += Jc.transpose() * wr;
          Hcp_[s].noalias() = Jc.transpose() * (w * Jp);
        }
      }
      mirrorUpper<3>(&H);
      Hpp_[j] = H;
      gp_[j] = g;
    }
    cost_t[t] = cost;
  });
  double cost = 0.0;
  for (int t = 0; t < T; ++t) cost += cost_t[t];
  for (int i = 0; i < ncf; ++i) {
    Hcc_[i] = Hcc_t_[0][i];
    gc_[i] = gc_t_[0][i];
    for (int t = 1; t < T; ++t) {
      Hcc_[i] += Hcc_t_[t][i];
      gc_[i] += gc_t_[t][i];
    }
  }
  // Free cameras observing fixed points.
  for (int k : cam_only_obs_) {
    const BaObservation& o = P_.observations[k];
    const int ci = cam_var_[o.camera];
    const Eigen::Vector3d p_c = Rt_[o.camera] * (P_.points[o.point].p_w - t_[o.camera]);
    if (p_c.z() <= kMinDepth) {
      cost += kernel_.sigma2;
      continue;
    }
    const Eigen::Vector2d r = o.uv - K_.project(p_c);
    const double sq = r.squaredNorm();
    cost += kernel_.rho(sq);
    const double w = kernel_.weight(sq);
    geometry::Matrix26d Jc;
    geometry::reprojectionJacobians(K_, p_c, R_[o.camera], &Jc, nullptr);
    addUpperJtJ<6>(Jc, w, &Hcc_[ci]);
    gc_[ci].noalias() += Jc.transpose() * (w * r);
  }
  for (int i = 0; i < ncf; ++i) mirrorUpper<6>(&Hcc_[i]);
  return cost;
}

double SubspaceGn::refinePoints(int iterations) {
  cacheCameras();
  const int T = std::max(1, O_.threads);
  std::vector<double> gain_t(T, 0.0);
  parallelFor(freePoints(), T, [&](int begin, int end, int t) {
    for (int j = begin; j < end; ++j) {
      Eigen::Vector3d p = P_.points[pts_[j]].p_w;
      auto eval = [&](const Eigen::Vector3d& x, Eigen::Matrix3d* H, Eigen::Vector3d* g) {
        double c = 0.0;
        if (H) H->setZero(), g->setZero();
        for (int a = pt_begin_[j]; a < pt_begin_[j + 1]; ++a) {
          const int cam = obs_cam_[a];
          const Eigen::Vector3d p_c = Rt_[cam] * (x - t_[cam]);
          if (p_c.z() <= kMinDepth) {
            c += kernel_.sigma2;
            continue;
          }
          const Eigen::Vector2d r = obs_uv_[a] - K_.project(p_c);
          const double sq = r.squaredNorm();
          c += kernel_.rho(sq);
          if (!H) continue;
          const geometry::Matrix23d Jp = -K_.jacobian(p_c) * Rt_[cam];
          const double w = kernel_.weight(sq);
          addUpperJtJ<3>(Jp, w, H);
          g->noalias() += Jp.transpose() * (w * r);
        }
        if (H) mirrorUpper<3>(H);
        return c;
      };
      double lambda = O_.initial_lambda;
      Eigen::Matrix3d H;
      Eigen::Vector3d g;
      for (int it = 0; it < iterations; ++it) {
        const double c0 = eval(p, &H, &g);
        bool improved = false;
        double gain = 0.0;
        for (int attempt = 0; attempt < 3 && !improved; ++attempt) {
          Eigen::Matrix3d Hd = H;
          Hd.diagonal() = Hd.diagonal() * (1.0 + lambda) + Eigen::Vector3d::Constant(1e-12 * (1.0 + H.trace()));
          const Eigen::Vector3d dp = -(Hd.inverse() * g);
          double c1 = eval(p + dp, nullptr, nullptr);
          if (c1 < c0) {
            // The IRLS model over-estimates the curvature of Geman-McClure (rho'' < 0), so its
            // steps fall short: try doubling the step while the cost keeps decreasing.
            double scale = 1.0;
            for (int e = 0; e < O_.point_extrapolation; ++e) {
              const double c2 = eval(p + (2.0 * scale) * dp, nullptr, nullptr);
              if (!(c2 < c1)) break;
              c1 = c2;
              scale *= 2.0;
            }
            p += scale * dp;
            gain = c0 - c1;
            gain_t[t] += gain;
            lambda *= 0.3;
            improved = true;
          } else {
            lambda *= 10.0;
          }
        }
        if (!improved || gain <= O_.point_tolerance * c0) break;
      }
      P_.points[pts_[j]].p_w = p;
    }
  });
  double gain = 0.0;
  for (double v : gain_t) gain += v;
  return gain;
}

void SubspaceGn::cacheCameras() {
  const size_t nc = P_.cameras.size();
  Rt_.resize(nc);
  R_.resize(nc);
  t_.resize(nc);
  for (size_t c = 0; c < nc; ++c) {
    R_[c] = P_.cameras[c].T_w_c.linear();
    Rt_[c] = R_[c].transpose();
    t_[c] = P_.cameras[c].T_w_c.translation();
  }
}

void SubspaceGn::saveState() {
  saved_cams_.resize(cams_.size());
  saved_pts_.resize(pts_.size());
  for (size_t i = 0; i < cams_.size(); ++i) saved_cams_[i] = P_.cameras[cams_[i]].T_w_c;
  for (size_t j = 0; j < pts_.size(); ++j) saved_pts_[j] = P_.points[pts_[j]].p_w;
}

void SubspaceGn::restoreState() {
  for (size_t i = 0; i < cams_.size(); ++i) P_.cameras[cams_[i]].T_w_c = saved_cams_[i];
  for (size_t j = 0; j < pts_.size(); ++j) P_.points[pts_[j]].p_w = saved_pts_[j];
}

void SubspaceGn::applyStep() {
  for (size_t i = 0; i < cams_.size(); ++i) {
    Eigen::Isometry3d& T = P_.cameras[cams_[i]].T_w_c;
    T = geometry::normalizedIsometry(T * geometry::expSE3(dc_[i]));
  }
  for (size_t j = 0; j < pts_.size(); ++j) P_.points[pts_[j]].p_w += dp_[j];
}

double SubspaceGn::activeCost() {
  cacheCameras();
  const int T = std::max(1, O_.threads);
  std::vector<double> cost_t(T, 0.0);
  auto term = [&](int cam, const Eigen::Vector3d& p_w, const Eigen::Vector2d& uv) {
    const Eigen::Vector3d p_c = Rt_[cam] * (p_w - t_[cam]);
    if (p_c.z() <= kMinDepth) return kernel_.sigma2;
    return kernel_.rho((uv - K_.project(p_c)).squaredNorm());
  };
  parallelFor(freePoints(), T, [&](int begin, int end, int t) {
    double c = 0.0;
    for (int j = begin; j < end; ++j) {
      const Eigen::Vector3d p = P_.points[pts_[j]].p_w;
      for (int a = pt_begin_[j]; a < pt_begin_[j + 1]; ++a) c += term(obs_cam_[a], p, obs_uv_[a]);
    }
    cost_t[t] = c;
  });
  double cost = 0.0;
  for (double c : cost_t) cost += c;
  for (int k : cam_only_obs_) {
    const BaObservation& o = P_.observations[k];
    cost += term(o.camera, P_.points[o.point].p_w, o.uv);
  }
  return cost;
}

}  // namespace detail

}  // namespace optimization
}  // namespace vitamin_e
