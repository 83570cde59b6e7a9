#pragma once
// NLTGV2-L1 denoising of a FrameMesh's inverse depths (after Greene & Roy,
// FLaME, ICCV 2017; non-local TGV of Ranftl et al.): every vertex i carries its
// inverse depth xi_i and a 2D gradient w_i (per normalized image coordinate);
// every mesh edge (i, j) penalises (symmetric form: the mean gradient of its ends)
//   alpha_ij * |xi_i - xi_j - (w_i + w_j)/2 . (x_i - x_j)| + beta * |w_i - w_j|_1
// (x = normalized coordinates), and every vertex lambda * |xi_i - z_i| (z: the
// measured inverse depth). As in NLTGV (Ranftl et al. 2014) the edge terms carry
// support weights: alpha_ij = alpha * max(min_support, exp(-(r_ij / support_sigma)^2))
// with r_ij the relative residual of each end's 1-ring plane fit (least squares
// on the 1-ring median-filtered measured inverse depths) predicting the other
// end: creases and slanted planes stay connected, object boundaries are cut, and
// single outliers (removed by the median) stay connected and are repaired.
// Gradients start from that plane fit. Piecewise-planar surfaces are flattened
// (affine inverse depth = plane) while steps are kept. Solved with the
// diagonally preconditioned primal-dual algorithm of Pock & Chambolle (2011).
// Inverse depths are solved relative to their median, so the result does not
// depend on the map unit (alpha, beta, lambda are unit-free).
// Warm start by track id: the edge duals, and optionally (warm_start_primal)
// the previous relative correction xi/z and gradient (the camera moved, so the
// previous inverse depths themselves are not reusable).
#include <cstdint>
#include <vector>

#include "vitamin_e/common/id_map.h"
#include "vitamin_e/meshing/frame_mesh.h"

namespace vitamin_e::meshing {

struct NltgvConfig {
  double alpha = 1.0;              // weight of the first-order (affine) term
  double beta = 0.1;               // weight of the gradient smoothness term (normalized-coordinate units)
  double lambda = 1.0;             // weight of the L1 data term
  int iterations = 200;            // primal-dual iterations (cold start)
  int warm_iterations = 120;       // iterations when most vertices were warm-started
  double theta = 1.0;              // over-relaxation
  double support_sigma = 0.05;     // relative inverse-depth jump scale of the support weights (0: all 1)
  double min_support = 0.02;       // floor of the support weights
  bool warm_start = true;          // keep the solution by track id for the next call
  bool warm_start_primal = false;  // also start from the previous inverse depths/gradients (else only the duals)
  void validate() const;           // throws std::invalid_argument naming the key
};

struct NltgvStats {
  int iterations = 0;
  std::size_t warm_started = 0;  // vertices initialised from the previous call
  std::size_t edges = 0;
};

class NltgvDenoiser {
 public:
  explicit NltgvDenoiser(const NltgvConfig& config = {});
  // Replaces mesh->vertices[i].inv_depth by the smoothed value (the data term
  // is measured_inv_depth). Needs the intrinsics for normalized coordinates.
  NltgvStats denoise(FrameMesh* mesh, const camera::Pinhole& K);
  // Forgets the warm start.
  void reset();
  const NltgvConfig& config() const { return config_; }

 private:
  struct VertexState {
    double ratio;
    double wx, wy;
  };
  NltgvConfig config_;
  common::IdMap<VertexState> prev_vertices_;
  common::IdMap<Eigen::Vector3f> prev_duals_;  // key: hash of (id_i, id_j)
};

}  // namespace vitamin_e::meshing
