#include <Eigen/Dense>
#include <cmath>
#include <limits>

#include "subspace_gn_impl.h"
#include "subspace_gn_rows.h"

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
  Jc_.resize(slot_cam_.size());
  Wjp_.resize(slot_cam_.size());
  slot_w_.resize(slot_cam_.size());
  hdiag_.resize(ncf);
  // Constant cost of the observations with nothing free.
  // Their residual norms do not change either: kept for finish().
  fixed_cost_ = 0.0;
  fixed_norm_.assign(P_.observations.size(), -1.0);
  Eigen::Vector2d r;
  for (size_t k = 0; k < P_.observations.size(); ++k) {
    const BaObservation& o = P_.observations[k];
    if (cam_var_[o.camera] >= 0 || pt_var_[o.point] >= 0) continue;
    if (baResidual(P_, o, &r)) {
      const double s = r.squaredNorm();
      fixed_cost_ += kernel_.rho(s);
      fixed_norm_[k] = std::sqrt(s);
    } else {
      fixed_cost_ += kernel_.sigma2;
      fixed_norm_[k] = std::numeric_limits<double>::infinity();
    }
  }
}

namespace {

template <int N>
inline void mirrorUpper(Eigen::Matrix<double, N, N>* H) {
  for (int c = 0; c < N; ++c)
    for (int r = c + 1; r < N; ++r) (*H)(r, c) = (*H)(c, r);
}

}  // namespace

double SubspaceGn::linearize() {
  const int ncf = freeCameras();
  cacheCameras();
  const int T = chunks_;
  // With use_schur the observations of free points enter the camera blocks only through the
  // Schur complement's diagonal blocks, Jc^T (w I - M) Jc (solveStep): here only the diagonal
  // of their H_cc (for the damping) is summed. Free cameras' observations of fixed points
  // give full H_cc blocks.
  const bool schur = O_.use_schur;
  Hcc_t_.resize(T);
  gc_t_.resize(T);
  hdiag_t_.resize(T);
  for (int t = 0; t < T; ++t) {
    if (!schur) Hcc_t_[t].assign(ncf, Matrix6d::Zero());
    gc_t_[t].assign(ncf, Vector6d::Zero());
    hdiag_t_[t].assign(ncf, Vector6d::Zero());
  }
  std::vector<double> cost_t(T, 0.0);
  forChunks(split_obs_, [&](int begin, int end, int t) {
    // The two residual rows side by side in 2-wide arrays (as evalPoint; SSE2 on x86-64), the
    // per-point accumulators summed once per point, the rows stored straight into Jc_/Wjp_.
    using A2 = Eigen::Array2d;
    using C2 = Eigen::Map<const A2>;
    using V2 = Eigen::Map<A2>;
    const double s2 = kernel_.sigma2;
    const A2 fxy(K_.fx, K_.fy), cxy(K_.cx, K_.cy);
    double cost = 0.0;
    Matrix6d* Hcc = schur ? nullptr : Hcc_t_[t].data();
    Vector6d* gc = gc_t_[t].data();
    Vector6d* hdiag = hdiag_t_[t].data();
    for (int j = begin; j < end; ++j) {
      PointBlockRows block;
      const Eigen::Vector3d& pw = P_.points[pts_[j]].p_w;
      const double px = pw.x(), py = pw.y(), pz = pw.z();
      for (int a = pt_begin_[j]; a < pt_begin_[j + 1]; ++a) {
        const int s = obs_slot_[a];
        const double* q = cam_pack_[obs_cam_[a]].data();
        const double d0 = px - q[9], d1 = py - q[10], d2 = pz - q[11];
        const double z = q[6] * d0 + q[7] * d1 + q[8] * d2;
        if (z <= kMinDepth) {
          cost += s2;
          if (s >= 0) {
            Jc_[s].setZero();
            Wjp_[s].setZero();
            slot_w_[s] = 0.0;
          }
          continue;
        }
        ObservationRows o;
        o.evaluate(q, d0, d1, d2, z, obs_uv_[a].data(), fxy, cxy, s2);
        cost += o.rho;
        block.add(o);
        if (s < 0) continue;
        const A2& wr = o.wr;
        const A2 &wj0 = o.wj0, &wj1 = o.wj1, &wj2 = o.wj2;
        const double w = o.w;
        const int ci = slot_cam_[s];
        double* J = Jc_[s].data();
        o.cameraColumns(z, J);
        double* W = Wjp_[s].data();
        V2(W + 0) = wj0;
        V2(W + 2) = wj1;
        V2(W + 4) = wj2;
        slot_w_[s] = w;
        double* G = gc[ci].data();
        double* Hd = hdiag[ci].data();
        for (int l = 0; l < 6; ++l) {
          const A2 col = C2(J + 2 * std::ptrdiff_t{l});
          G[l] += (col * wr).sum();
          Hd[l] += w * (col * col).sum();
        }
        if (Hcc) {
          Matrix6d& Hc = Hcc[ci];
          for (int l = 0; l < 6; ++l)
            for (int k = 0; k <= l; ++k)
              Hc(k, l) += w * (J[2 * std::ptrdiff_t{k}] * J[2 * std::ptrdiff_t{l}] + J[2 * k + 1] * J[2 * l + 1]);
        }
      }
      block.sum(&Hpp_[j], &gp_[j]);
    }
    cost_t[t] = cost;
  });
  double cost = 0.0;
  for (int t = 0; t < T; ++t) cost += cost_t[t];
  for (int i = 0; i < ncf; ++i) {
    Hcc_[i] = schur ? Matrix6d::Zero() : Hcc_t_[0][i];
    gc_[i] = gc_t_[0][i];
    hdiag_[i] = hdiag_t_[0][i];
    for (int t = 1; t < T; ++t) {
      if (!schur) Hcc_[i] += Hcc_t_[t][i];
      gc_[i] += gc_t_[t][i];
      hdiag_[i] += hdiag_t_[t][i];
    }
  }
  // Free cameras observing fixed points.
  for (int k : cam_only_obs_) {
    const BaObservation& o = P_.observations[k];
    const int ci = cam_var_[o.camera];
    ObsEval e;
    if (!e.residual(K_, kernel_.sigma2, R_[o.camera], t_[o.camera], P_.points[o.point].p_w, o.uv)) {
      cost += kernel_.sigma2;
      continue;
    }
    cost += e.rho(kernel_.sigma2);
    e.addCamera(e.weight(kernel_.sigma2), &Hcc_[ci], nullptr, &gc_[ci], nullptr, nullptr);
  }
  for (int i = 0; i < ncf; ++i) {
    mirrorUpper<6>(&Hcc_[i]);
    // Diagonal of the whole H_cc (the Schur path's slot part plus the full blocks).
    if (schur) hdiag_[i] += Hcc_[i].diagonal();
    else hdiag_[i] = Hcc_[i].diagonal();
  }
  return cost;
}

double SubspaceGn::evalPoint(int j, const Eigen::Vector3d& xw, Eigen::Matrix3d* H, Eigen::Vector3d* g) const {
  // Scalars, as in linearize(); the cost-only loop is the refinement's line search.
  const double fx = K_.fx, fy = K_.fy, cx = K_.cx, cy = K_.cy, s2 = kernel_.sigma2;
  const double px = xw.x(), py = xw.y(), pz = xw.z();
  const int a0 = pt_begin_[j], a1 = pt_begin_[j + 1];
  double c = 0.0;
  using A2 = Eigen::Array2d;
  using C2 = Eigen::Map<const A2>;
  const A2 fxy(fx, fy), cxy(cx, cy);
  if (!H) {
    for (int a = a0; a < a1; ++a) {
      const double* q = cam_pack_[obs_cam_[a]].data();
      const double d0 = px - q[9], d1 = py - q[10], d2 = pz - q[11];
      const double z = q[6] * d0 + q[7] * d1 + q[8] * d2;
      if (z <= kMinDepth) {
        c += s2;
        continue;
      }
      const A2 xy = C2(q) * d0 + C2(q + 2) * d1 + C2(q + 4) * d2;
      const A2 r = C2(obs_uv_[a].data()) - (fxy * (1.0 / z) * xy + cxy);
      const double sq = r(0) * r(0) + r(1) * r(1);
      c += s2 * sq * (1.0 / (s2 + sq));
    }
    return c;
  }
  PointBlockRows block;
  for (int a = a0; a < a1; ++a) {
    const double* q = cam_pack_[obs_cam_[a]].data();
    const double d0 = px - q[9], d1 = py - q[10], d2 = pz - q[11];
    const double z = q[6] * d0 + q[7] * d1 + q[8] * d2;
    if (z <= kMinDepth) {
      c += s2;
      continue;
    }
    ObservationRows o;
    o.evaluate(q, d0, d1, d2, z, obs_uv_[a].data(), fxy, cxy, s2);
    c += o.rho;
    block.add(o);
  }
  block.sum(H, g);
  return c;
}

double SubspaceGn::refinePoints(int iterations) {
  cacheCameras();
  const int T = chunks_;
  std::vector<double> gain_t(T, 0.0);
  forChunks(split_obs_, [&](int begin, int end, int t) {
    for (int j = begin; j < end; ++j) {
      Eigen::Vector3d p = P_.points[pts_[j]].p_w;
      double lambda = O_.initial_lambda;
      // The first linearization is activeCost's, at this same estimate.
      Eigen::Matrix3d H = ref_H_[j];
      Eigen::Vector3d g = ref_g_[j];
      double c0 = ref_c_[j];
      for (int it = 0; it < iterations; ++it) {
        if (it > 0) c0 = evalPoint(j, p, &H, &g);
        bool improved = false;
        double gain = 0.0;
        for (int attempt = 0; attempt < 3 && !improved; ++attempt) {
          Eigen::Matrix3d Hd = H;
          Hd.diagonal() = Hd.diagonal() * (1.0 + lambda) + Eigen::Vector3d::Constant(1e-12 * (1.0 + H.trace()));
          const Eigen::Vector3d dp = -(Hd.inverse() * g);
          double c1 = evalPoint(j, p + dp, nullptr, nullptr);
          if (c1 < c0) {
            // The IRLS model over-estimates the curvature of Geman-McClure (rho'' < 0), so its
            // steps fall short: try doubling the step while the cost keeps decreasing.
            double scale = 1.0;
            for (int e = 0; e < O_.point_extrapolation; ++e) {
              const double c2 = evalPoint(j, p + (2.0 * scale) * dp, nullptr, nullptr);
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
  R_.resize(nc);
  t_.resize(nc);
  cam_pack_.resize(nc);
  for (size_t c = 0; c < nc; ++c) {
    R_[c] = P_.cameras[c].T_w_c.linear();
    t_[c] = P_.cameras[c].T_w_c.translation();
    cam_pack_[c] = packCamera(R_[c], t_[c]);
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
  const int T = chunks_;
  const bool keep = O_.point_iterations > 0;
  if (keep) {
    ref_H_.resize(pts_.size());
    ref_g_.resize(pts_.size());
    ref_c_.resize(pts_.size());
  }
  std::vector<double> cost_t(T, 0.0);
  forChunks(split_obs_, [&](int begin, int end, int t) {
    double c = 0.0;
    for (int j = begin; j < end; ++j) {
      const Eigen::Vector3d& p = P_.points[pts_[j]].p_w;
      if (keep) {
        ref_c_[j] = evalPoint(j, p, &ref_H_[j], &ref_g_[j]);
        c += ref_c_[j];
      } else {
        c += evalPoint(j, p, nullptr, nullptr);
      }
    }
    cost_t[t] = c;
  });
  double cost = 0.0;
  for (double c : cost_t) cost += c;
  for (int k : cam_only_obs_) {
    const BaObservation& o = P_.observations[k];
    ObsEval e;
    cost += e.residual(K_, kernel_.sigma2, R_[o.camera], t_[o.camera], P_.points[o.point].p_w, o.uv)
                ? e.rho(kernel_.sigma2)
                : kernel_.sigma2;
  }
  return cost;
}

}  // namespace detail

}  // namespace optimization
}  // namespace vitamin_e
