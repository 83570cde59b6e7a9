#include "vitamin_e/optimization/block_solvers.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

namespace vitamin_e {
namespace optimization {

using geometry::Matrix6d;
using geometry::Vector6d;
using Blocks = std::vector<Vector6d>;

namespace {

std::vector<Eigen::LDLT<Matrix6d>> factorDiagonal(const BlockMatrix6& A) {
  std::vector<Eigen::LDLT<Matrix6d>> f(A.n);
  for (int i = 0; i < A.n; ++i) f[i].compute(A.at(i, i));
  return f;
}

double dot(const Blocks& a, const Blocks& b) {
  double d = 0.0;
  for (size_t i = 0; i < a.size(); ++i) d += a[i].dot(b[i]);
  return d;
}

}  // namespace

int solveBlockGaussSeidel(const BlockMatrix6& A, const Blocks& b, int max_passes, double tolerance, Blocks* x) {
  const int n = A.n;
  if (static_cast<int>(x->size()) != n) x->assign(n, Vector6d::Zero());
  const auto diag = factorDiagonal(A);
  int pass = 0;
  while (pass < max_passes) {
    ++pass;
    double max_change = 0.0, max_x = 0.0;
    for (int i = 0; i < n; ++i) {
      Vector6d rhs = b[i];
      for (int l = 0; l < n; ++l)
        if (l != i) rhs.noalias() -= A.at(i, l) * (*x)[l];
      const Vector6d xi = diag[i].solve(rhs);
      max_change = std::max(max_change, (xi - (*x)[i]).lpNorm<Eigen::Infinity>());
      max_x = std::max(max_x, xi.lpNorm<Eigen::Infinity>());
      (*x)[i] = xi;
    }
    if (max_change <= tolerance * max_x) break;
  }
  return pass;
}

int solveBlockPcg(const BlockMatrix6& A, const Blocks& b, int max_iterations, double tolerance, Blocks* x) {
  const int n = A.n;
  x->assign(n, Vector6d::Zero());
  const auto diag = factorDiagonal(A);
  Blocks r = b, z(n), p(n), Ap(n);
  for (int i = 0; i < n; ++i) z[i] = diag[i].solve(r[i]);
  p = z;
  double rz = dot(r, z);
  const double b_norm = std::sqrt(dot(b, b));
  if (b_norm == 0.0) return 0;
  int it = 0;
  while (it < max_iterations && rz > 0.0) {
    ++it;
    for (int i = 0; i < n; ++i) {
      Ap[i].setZero();
      for (int l = 0; l < n; ++l) Ap[i].noalias() += A.at(i, l) * p[l];
    }
    const double p_A_p = dot(p, Ap);
    if (!(p_A_p > 0.0)) break;
    const double alpha = rz / p_A_p;
    for (int i = 0; i < n; ++i) {
      (*x)[i].noalias() += alpha * p[i];
      r[i].noalias() -= alpha * Ap[i];
    }
    if (std::sqrt(dot(r, r)) <= tolerance * b_norm) break;
    for (int i = 0; i < n; ++i) z[i] = diag[i].solve(r[i]);
    const double rz_new = dot(r, z);
    const double beta = rz_new / rz;
    rz = rz_new;
    for (int i = 0; i < n; ++i) p[i] = z[i] + beta * p[i];
  }
  return it;
}

}  // namespace optimization
}  // namespace vitamin_e
