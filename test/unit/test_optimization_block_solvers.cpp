#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>

#include "vitamin_e/optimization/block_solvers.h"

using namespace vitamin_e::optimization;
using vitamin_e::geometry::Vector6d;

namespace {

// A random SPD system of n 6x6 blocks, coupled like a chain of cameras sharing points.
BlockMatrix6 randomSpd(int n, unsigned seed, Eigen::MatrixXd* dense) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::MatrixXd J(12 * n, 6 * n);
  J.setZero();
  for (int r = 0; r < 12 * n; ++r) {
    const int c0 = 6 * ((r / 12) % n), c1 = 6 * (((r / 12) + 1) % n);
    for (int k = 0; k < 6; ++k) {
      J(r, c0 + k) = g(rng);
      J(r, c1 + k) = 0.8 * g(rng);
    }
  }
  *dense = J.transpose() * J +
           1e-3 * Eigen::MatrixXd::Identity(6 * static_cast<Eigen::Index>(n), 6 * static_cast<Eigen::Index>(n));
  BlockMatrix6 A;
  A.resize(n);
  for (int i = 0; i < n; ++i)
    for (int l = 0; l < n; ++l)
      A.at(i, l) = dense->block<6, 6>(6 * static_cast<Eigen::Index>(i), 6 * static_cast<Eigen::Index>(l));
  return A;
}

double error(const std::vector<Vector6d>& x, const Eigen::VectorXd& ref) {
  double e = 0.0;
  for (size_t i = 0; i < x.size(); ++i)
    e = std::max(e, (x[i] - ref.segment<6>(static_cast<Eigen::Index>(6 * i))).lpNorm<Eigen::Infinity>());
  return e / ref.lpNorm<Eigen::Infinity>();
}

}  // namespace

TEST(BlockSolvers, PcgAndGaussSeidelMatchDenseSolve) {
  const int n = 8;
  Eigen::MatrixXd D;
  const BlockMatrix6 A = randomSpd(n, 3, &D);
  std::mt19937 rng(5);
  std::normal_distribution<double> g(0.0, 1.0);
  std::vector<Vector6d> b(n);
  Eigen::VectorXd bd(6 * n);
  for (int i = 0; i < n; ++i) {
    for (int k = 0; k < 6; ++k) b[i](k) = g(rng);
    bd.segment<6>(6 * static_cast<Eigen::Index>(i)) = b[i];
  }
  const Eigen::VectorXd ref = D.ldlt().solve(bd);

  std::vector<Vector6d> x;
  const int it = solveBlockPcg(A, b, 500, 1e-12, &x);
  EXPECT_LE(it, 6 * n + 5);  // exact in at most 6n steps in exact arithmetic
  EXPECT_LT(error(x, ref), 1e-8);

  std::vector<Vector6d> y;
  const int passes = solveBlockGaussSeidel(A, b, 20000, 1e-13, &y);
  EXPECT_LT(error(y, ref), 1e-7);
  EXPECT_GT(passes, it);  // Gauss-Seidel needs more passes on a coupled chain

  // A single pass of Gauss-Seidel is not the solution: the tests above can fail.
  std::vector<Vector6d> z;
  solveBlockGaussSeidel(A, b, 1, 0.0, &z);
  EXPECT_GT(error(z, ref), 1e-3);
}

TEST(BlockSolvers, DiagonalSystemIsSolvedInOneStep) {
  BlockMatrix6 A;
  A.resize(3);
  std::vector<Vector6d> b(3, Vector6d::Ones());
  for (int i = 0; i < 3; ++i) A.at(i, i) = (i + 1.0) * vitamin_e::geometry::Matrix6d::Identity();
  std::vector<Vector6d> x;
  EXPECT_EQ(solveBlockPcg(A, b, 10, 1e-12, &x), 1);
  for (int i = 0; i < 3; ++i) EXPECT_LT((x[i] - Vector6d::Constant(1.0 / (i + 1))).norm(), 1e-14);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
