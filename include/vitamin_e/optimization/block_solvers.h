#pragma once
// Iterative solvers for a symmetric positive definite system made of 6x6 blocks (the reduced
// camera system of bundle adjustment after the points are eliminated). Only 6x6 diagonal
// blocks are ever factorized: no large matrix is inverted.
#include <Eigen/Core>
#include <vector>

#include "vitamin_e/geometry/lie.h"

namespace vitamin_e {
namespace optimization {

// n x n blocks of 6x6, dense row-major block storage (n is the number of free cameras).
struct BlockMatrix6 {
  int n = 0;
  std::vector<geometry::Matrix6d> blocks;
  void resize(int size) {
    n = size;
    blocks.assign(static_cast<size_t>(size) * size, geometry::Matrix6d::Zero());
  }
  geometry::Matrix6d& at(int i, int j) { return blocks[static_cast<size_t>(i) * n + j]; }
  const geometry::Matrix6d& at(int i, int j) const { return blocks[static_cast<size_t>(i) * n + j]; }
};

// Block Gauss-Seidel (paper Eq. 11 on the reduced system): x_i = A_ii^-1 (b_i - sum_{l!=i} A_il x_l),
// in order, using the newest x_l. Starts from *x (resized/zeroed if its size differs). Stops
// after max_passes or when max_i |change_i|_inf <= tolerance * max_i |x_i|_inf.
// Returns the number of passes.
int solveBlockGaussSeidel(const BlockMatrix6& A, const std::vector<geometry::Vector6d>& b, int max_passes,
                          double tolerance, std::vector<geometry::Vector6d>* x);

// Conjugate gradients preconditioned by the inverse diagonal blocks (block Jacobi), from x = 0.
// Stops after max_iterations or when |b - A x| <= tolerance * |b|. Returns the iterations.
int solveBlockPcg(const BlockMatrix6& A, const std::vector<geometry::Vector6d>& b, int max_iterations, double tolerance,
                  std::vector<geometry::Vector6d>* x);

}  // namespace optimization
}  // namespace vitamin_e
