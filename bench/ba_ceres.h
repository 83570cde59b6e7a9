#pragma once
// The Ceres reference of bench_optimization_ba (benchmark only): the same BA problem with an
// SE(3) right-perturbation manifold, analytic reprojection Jacobians (the shared formulas of
// geometry/projection.h) and the same Geman-McClure loss, solved by Levenberg-Marquardt.
#include <algorithm>
#include <vector>
#include "vitamin_e/common/timing.h"

#include "vitamin_e/geometry/lie.h"
#include "vitamin_e/geometry/projection.h"
#include "vitamin_e/optimization/ba_problem.h"

#ifdef VITAMIN_E_WITH_CERES
#include <ceres/ceres.h>

namespace vitamin_e {
namespace bench {

using optimization::BaObservation;
using optimization::BaProblem;


// T_w_c as [t(3), q(4: x y z w)], tangent = right se(3) perturbation (rho, phi) as in lie.h.
// The cost returns the tangent Jacobian in the first 6 columns and PlusJacobian = [I6; 0].
class Se3RightManifold : public ceres::Manifold {
 public:
  int AmbientSize() const override { return 7; }
  int TangentSize() const override { return 6; }
  bool Plus(const double* x, const double* delta, double* x_plus) const override {
    const Eigen::Isometry3d T = fromParams(x) * geometry::expSE3(Eigen::Map<const geometry::Vector6d>(delta));
    toParams(T, x_plus);
    return true;
  }
  bool PlusJacobian(const double*, double* J) const override {
    Eigen::Map<Eigen::Matrix<double, 7, 6, Eigen::RowMajor>> M(J);
    M.setZero();
    M.topRows<6>().setIdentity();
    return true;
  }
  bool Minus(const double* y, const double* x, double* d) const override {
    Eigen::Map<geometry::Vector6d> out(d);
    out = geometry::logSE3(fromParams(x).inverse() * fromParams(y));
    return true;
  }
  bool MinusJacobian(const double*, double* J) const override {
    Eigen::Map<Eigen::Matrix<double, 6, 7, Eigen::RowMajor>> M(J);
    M.setZero();
    M.leftCols<6>().setIdentity();
    return true;
  }
  static Eigen::Isometry3d fromParams(const double* x) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.translation() = Eigen::Vector3d(x[0], x[1], x[2]);
    T.linear() = Eigen::Quaterniond(x[6], x[3], x[4], x[5]).normalized().toRotationMatrix();
    return T;
  }
  static void toParams(const Eigen::Isometry3d& T, double* x) {
    const Eigen::Quaterniond q(T.linear());
    x[0] = T.translation().x();
    x[1] = T.translation().y();
    x[2] = T.translation().z();
    x[3] = q.x();
    x[4] = q.y();
    x[5] = q.z();
    x[6] = q.w();
  }
};

class ReprojectionCost : public ceres::SizedCostFunction<2, 7, 3> {
 public:
  ReprojectionCost(const camera::Pinhole& K, const Eigen::Vector2d& uv) : K_(K), uv_(uv) {}
  bool Evaluate(double const* const* params, double* residuals, double** jacobians) const override {
    const Eigen::Isometry3d T_w_c = Se3RightManifold::fromParams(params[0]);
    const Eigen::Vector3d p_w(params[1][0], params[1][1], params[1][2]);
    const Eigen::Vector3d p_c = T_w_c.linear().transpose() * (p_w - T_w_c.translation());
    if (p_c.z() <= 1e-9) {  // behind the camera: saturate the loss like baCost, no gradient
      residuals[0] = residuals[1] = 1e6;
      if (jacobians && jacobians[0]) std::fill(jacobians[0], jacobians[0] + 14, 0.0);
      if (jacobians && jacobians[1]) std::fill(jacobians[1], jacobians[1] + 6, 0.0);
      return true;
    }
    Eigen::Map<Eigen::Vector2d> res(residuals);
    res = uv_ - K_.projectPoint(p_c);
    if (jacobians) {
      geometry::Matrix26d Jc;
      geometry::Matrix23d Jp;
      geometry::reprojectionJacobians(K_, p_c, T_w_c.linear(), &Jc, &Jp);
      if (jacobians[0]) {
        Eigen::Map<Eigen::Matrix<double, 2, 7, Eigen::RowMajor>> J(jacobians[0]);
        J.leftCols<6>() = Jc;
        J.col(6).setZero();
      }
      if (jacobians[1]) {
        Eigen::Map<Eigen::Matrix<double, 2, 3, Eigen::RowMajor>> J(jacobians[1]);
        J = Jp;
      }
    }
    return true;
  }

 private:
  camera::Pinhole K_;
  Eigen::Vector2d uv_;
};

// rho(s) = sigma^2 s / (sigma^2 + s): the same Geman-McClure as baCost (Ceres adds the 1/2).
class GemanMcClureLoss : public ceres::LossFunction {
 public:
  explicit GemanMcClureLoss(double sigma) : k_(sigma) {}
  void Evaluate(double s, double rho[3]) const override {
    rho[0] = k_.rho(s);
    rho[1] = k_.weight(s);
    rho[2] = k_.second(s);
  }

 private:
  geometry::GemanMcClure k_;
};

// Solves `problem` in place with Ceres; returns wall time (problem construction + Solve).
inline double solveCeres(BaProblem& problem, double sigma, double tolerance, bool sparse, int threads,
                         int* iterations) {
  const auto t0 = TimingClock::now();
  std::vector<double> cams(7 * problem.cameras.size()), pts(3 * problem.points.size());
  for (size_t c = 0; c < problem.cameras.size(); ++c)
    Se3RightManifold::toParams(problem.cameras[c].T_w_c, &cams[7 * c]);
  for (size_t p = 0; p < problem.points.size(); ++p) {
    Eigen::Map<Eigen::Vector3d> m(&pts[3 * p]);
    m = problem.points[p].p_w;
  }
  ceres::Problem::Options popt;
  popt.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem cp(popt);
  GemanMcClureLoss loss(sigma);
  auto* manifold = new Se3RightManifold();
  std::vector<bool> cam_added(problem.cameras.size(), false);
  for (const BaObservation& o : problem.observations) {
    if (problem.cameras[o.camera].fixed && problem.points[o.point].fixed) continue;  // constant term
    double* cam = &cams[7 * static_cast<std::size_t>(o.camera)];
    double* pt = &pts[3 * static_cast<std::size_t>(o.point)];
    cp.AddResidualBlock(new ReprojectionCost(problem.K, o.uv), &loss, cam, pt);
    if (!cam_added[o.camera]) {
      cam_added[o.camera] = true;
      cp.SetManifold(cam, manifold);
      if (problem.cameras[o.camera].fixed) cp.SetParameterBlockConstant(cam);
    }
    if (problem.points[o.point].fixed) cp.SetParameterBlockConstant(pt);
  }
  if (!std::any_of(cam_added.begin(), cam_added.end(), [](bool b) { return b; })) delete manifold;
  ceres::Solver::Options opt;
  opt.minimizer_type = ceres::TRUST_REGION;
  opt.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  opt.linear_solver_type = sparse ? ceres::SPARSE_SCHUR : ceres::DENSE_SCHUR;
  opt.function_tolerance = tolerance;
  opt.max_num_iterations = 50;
  opt.num_threads = threads;
  opt.logging_type = ceres::SILENT;
  ceres::Solver::Summary sum;
  ceres::Solve(opt, &cp, &sum);
  for (size_t c = 0; c < problem.cameras.size(); ++c)
    problem.cameras[c].T_w_c = Se3RightManifold::fromParams(&cams[7 * c]);
  for (size_t p = 0; p < problem.points.size(); ++p) problem.points[p].p_w = Eigen::Map<Eigen::Vector3d>(&pts[3 * p]);
  *iterations = static_cast<int>(sum.iterations.size());
  return elapsedMs(t0);
}

}  // namespace bench
}  // namespace vitamin_e
#endif  // VITAMIN_E_WITH_CERES
