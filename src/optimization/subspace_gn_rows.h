#pragma once
// Internal to vitamin_e_optimization: the inlined derivatives of the subspace
// Gauss-Newton linearization (subspace_gn_linearize.cpp), one observation at a
// time: the reprojection residual, its Geman-McClure cost and IRLS weight, and
// the rows of d r / d p_w and d r / d camera, written out in scalars (ObsEval)
// and as two-wide arrays (ObservationRows). In a header of their own so that
// test_optimization_jacobians checks each against numeric derivatives.
#include <Eigen/Core>
#include <array>

#include "subspace_gn_impl.h"

namespace vitamin_e {
namespace optimization {
namespace detail {

// A camera as ObservationRows reads it: the first two columns of R_w_c interleaved,
// (R00, R01, R10, R11, R20, R21), then its third column (R02, R12, R22) and t_w_c. Row k
// of [x y]^T = R^T d is then one packed product per d_k.
inline std::array<double, 12> packCamera(const Eigen::Matrix3d& R, const Eigen::Vector3d& t) {
  const double* m = R.data();
  return {m[0], m[3], m[1], m[4], m[2], m[5], m[6], m[7], m[8], t.x(), t.y(), t.z()};
}

// One observation of a point at p_w in a camera (R = R_w_c column-major, t = t_w_c), written
// out in scalars: p_c = R^T (p_w - t), the residual r = uv - pi(p_c) and, from the sparsity
// of the pinhole Jacobian [A 0 B; 0 C D], the rows of d r / d p_w (jp0, jp1) and of
// d r / d camera (jc0, jc1, right-perturbation). Same formulas as reprojectionJacobians.
struct ObsEval {
  double x, y, z, r0, r1, sq, inv;  // inv = 1 / (sigma^2 + sq)
  double A, B, C, D;
  double jp0[3], jp1[3];

  // Returns false when the point is at depth <= min_depth (no residual).
  inline bool residual(const camera::Pinhole& K, double sigma2, const Eigen::Matrix3d& R, const Eigen::Vector3d& t,
                       const Eigen::Vector3d& p, const Eigen::Vector2d& uv) {
    const double* m = R.data();
    const double d0 = p.x() - t.x(), d1 = p.y() - t.y(), d2 = p.z() - t.z();
    x = m[0] * d0 + m[1] * d1 + m[2] * d2;
    y = m[3] * d0 + m[4] * d1 + m[5] * d2;
    z = m[6] * d0 + m[7] * d1 + m[8] * d2;
    if (z <= kMinDepth) return false;
    const double iz = 1.0 / z;
    A = K.fx * iz;
    C = K.fy * iz;
    r0 = uv.x() - (A * x + K.cx);
    r1 = uv.y() - (C * y + K.cy);
    sq = r0 * r0 + r1 * r1;
    inv = 1.0 / (sigma2 + sq);
    B = -A * x * iz;
    D = -C * y * iz;
    return true;
  }
  // Geman-McClure (geometry::GemanMcClure) from the one division: rho = sigma^2 s / (sigma^2 + s),
  // IRLS weight rho' = sigma^4 / (sigma^2 + s)^2.
  inline double rho(double sigma2) const { return sigma2 * sq * inv; }
  inline double weight(double sigma2) const { return sigma2 * sigma2 * inv * inv; }
  inline void pointJacobian(const Eigen::Matrix3d& R) {
    const double* m = R.data();
    for (int k = 0; k < 3; ++k) {
      jp0[k] = -(A * m[k] + B * m[6 + k]);
      jp1[k] = -(C * m[3 + k] + D * m[6 + k]);
    }
  }
  // H += w Jp^T Jp (upper triangle), g += w Jp^T r.
  inline void addPoint(double w, Eigen::Matrix3d* H, Eigen::Vector3d* g) const {
    const double wr0 = w * r0, wr1 = w * r1;
    for (int l = 0; l < 3; ++l) {
      const double a0 = w * jp0[l], a1 = w * jp1[l];
      for (int k = 0; k <= l; ++k) (*H)(k, l) += a0 * jp0[k] + a1 * jp1[k];
      (*g)(l) += jp0[l] * wr0 + jp1[l] * wr1;
    }
  }
  // Camera rows: Hcc += w Jc^T Jc (upper triangle; with Hcc null only its diagonal, into
  // hdiag), gc += w Jc^T r; with Jc/Wjp, stores the camera rows and the weighted point rows
  // (H_cp = Jc^T Wjp).
  inline void addCamera(double w, Matrix6d* Hcc, Vector6d* hdiag, Vector6d* gc, Matrix26d* Jc, Matrix23d* Wjp) const {
    const double jc0[6] = {A, 0.0, B, B * y, A * z - B * x, -A * y};
    const double jc1[6] = {0.0, C, D, D * y - C * z, -D * x, C * x};
    const double wr0 = w * r0, wr1 = w * r1;
    for (int l = 0; l < 6; ++l) {
      const double a0 = w * jc0[l], a1 = w * jc1[l];
      if (Hcc) {
        for (int k = 0; k <= l; ++k) (*Hcc)(k, l) += a0 * jc0[k] + a1 * jc1[k];
      } else {
        (*hdiag)(l) += a0 * jc0[l] + a1 * jc1[l];
      }
      (*gc)(l) += jc0[l] * wr0 + jc1[l] * wr1;
    }
    if (Jc) {
      for (int l = 0; l < 6; ++l) {
        (*Jc)(0, l) = jc0[l];
        (*Jc)(1, l) = jc1[l];
      }
      for (int m = 0; m < 3; ++m) {
        (*Wjp)(0, m) = w * jp0[m];
        (*Wjp)(1, m) = w * jp1[m];
      }
    }
  }
};


// One observation's two residual rows side by side in 2-wide arrays (SSE2 on x86-64), for a
// camera packed as q (R's rows interleaved as column pairs at 0..5, R's third row at 6..8,
// t at 9..11), d = p_w - t and depth z > kMinDepth: the pinhole Jacobian [A 0 B; 0 C D] as
// (A, C) and (B, D), the residual, its Geman-McClure cost and weight, and the columns of
// d r / d p_w, (row 0, row 1) each, plain and times the weight.
struct ObservationRows {
  using A2 = Eigen::Array2d;
  using C2 = Eigen::Map<const A2>;
  A2 xy, AC, BD, r, wr, j0, j1, j2, wj0, wj1, wj2;
  double rho = 0.0, w = 0.0;
  inline void evaluate(const double* q, double d0, double d1, double d2, double z, const double* uv, const A2& fxy,
                       const A2& cxy, double s2) {
    xy = C2(q) * d0 + C2(q + 2) * d1 + C2(q + 4) * d2;
    const double iz = 1.0 / z;
    AC = fxy * iz;
    r = C2(uv) - (AC * xy + cxy);
    const double sq = r(0) * r(0) + r(1) * r(1);
    const double inv = 1.0 / (s2 + sq);
    rho = s2 * sq * inv;
    w = s2 * s2 * inv * inv;
    BD = -AC * xy * iz;
    // Column k: -((A, C) * (R0k, R1k) + (B, D) * R2k).
    j0 = -(AC * C2(q) + BD * q[6]);
    j1 = -(AC * C2(q + 2) + BD * q[7]);
    j2 = -(AC * C2(q + 4) + BD * q[8]);
    wj0 = w * j0;
    wj1 = w * j1;
    wj2 = w * j2;
    wr = w * r;
  }
  // The columns of d r / d camera (right perturbation T_w_c exp(xi), xi = (translation,
  // rotation)) at depth z, column-major 2x6: column l at J + 2l. The same formulas as
  // ObsEval::addCamera.
  inline void cameraColumns(double z, double* J) const {
    const double A = AC(0), C = AC(1), B = BD(0), D = BD(1), x = xy(0), y = xy(1);
    J[0] = A;
    J[1] = 0.0;
    J[2] = 0.0;
    J[3] = C;
    J[4] = B;
    J[5] = D;
    J[6] = B * y;
    J[7] = D * y - C * z;
    J[8] = A * z - B * x;
    J[9] = -D * x;
    J[10] = -A * y;
    J[11] = C * x;
  }
};

// A point's 3x3 block and gradient, the two rows' terms kept apart and summed once per point.
struct PointBlockRows {
  using A2 = Eigen::Array2d;
  A2 H00 = A2::Zero(), H01 = A2::Zero(), H02 = A2::Zero(), H11 = A2::Zero(), H12 = A2::Zero(), H22 = A2::Zero();
  A2 G0 = A2::Zero(), G1 = A2::Zero(), G2 = A2::Zero();
  inline void add(const ObservationRows& o) {
    H00 += o.wj0 * o.j0;
    H01 += o.wj0 * o.j1;
    H02 += o.wj0 * o.j2;
    H11 += o.wj1 * o.j1;
    H12 += o.wj1 * o.j2;
    H22 += o.wj2 * o.j2;
    G0 += o.j0 * o.wr;
    G1 += o.j1 * o.wr;
    G2 += o.j2 * o.wr;
  }
  void sum(Eigen::Matrix3d* H, Eigen::Vector3d* g) const {
    const double h00 = H00.sum(), h01 = H01.sum(), h02 = H02.sum(), h11 = H11.sum(), h12 = H12.sum(), h22 = H22.sum();
    *H << h00, h01, h02, h01, h11, h12, h02, h12, h22;
    *g = Eigen::Vector3d(G0.sum(), G1.sum(), G2.sum());
  }
};

}  // namespace detail
}  // namespace optimization
}  // namespace vitamin_e
