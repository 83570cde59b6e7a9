// NLTGV2-L1 denoising: flattens noisy planes, keeps steps, warm start.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "vitamin_e/meshing/frame_mesher.h"
#include "vitamin_e/meshing/nltgv_denoiser.h"

using namespace vitamin_e::meshing;
using Eigen::Vector2d;
using Eigen::Vector3d;

namespace {
PinholeImage testImage() { return {{450.0, 450.0, 376.0, 240.0}, 752, 480}; }

// Jittered-grid pixels; true inverse depth from `truth`; multiplicative noise.
template <typename Truth>
FrameMesh noisyMesh(const Truth& truth, double noise, double outlier_rate, unsigned seed, std::vector<double>* true_inv,
                    bool cut_jumps = false) {
  const PinholeImage image = testImage();
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> J(-4.0, 4.0), U(0.0, 1.0);
  std::normal_distribution<double> N(0.0, noise);
  std::vector<std::uint64_t> ids;
  std::vector<Vector2d> uv;
  std::vector<double> depth;
  std::uint64_t id = 0;
  for (int y = 10; y < 470; y += 12)
    for (int x = 10; x < 742; x += 12) {
      const Vector2d p(x + J(rng), y + J(rng));
      double inv = truth(p);
      inv *= (U(rng) < outlier_rate) ? (U(rng) < 0.5 ? 0.6 : 1.5) : (1.0 + N(rng));
      ids.push_back(id++);
      uv.push_back(p);
      depth.push_back(1.0 / inv);
    }
  FrameMesherConfig cfg;
  cfg.max_edge_px = 40.0;
  cfg.max_normal_angle_deg = 90.0;
  cfg.max_inv_depth_jump = cut_jumps ? 0.25 : 10.0;
  cfg.drop_unused_vertices = false;
  FrameMesh mesh = FrameMesher(cfg).build(ids, uv, depth, image);
  true_inv->clear();
  for (const auto& v : mesh.vertices) true_inv->push_back(truth(v.uv));
  return mesh;
}

double meanAbsError(const FrameMesh& mesh, const std::vector<double>& truth, bool smoothed) {
  double s = 0.0;
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i)
    s += std::abs((smoothed ? mesh.vertices[i].inv_depth : mesh.vertices[i].measured_inv_depth) - truth[i]);
  return s / static_cast<double>(mesh.vertices.size());
}

// A slanted plane n . p = d in the camera frame: inverse depth is affine in the pixel.
auto slantedPlane() {
  const Vector3d n = Vector3d(0.3, -0.2, 1.0).normalized();
  const double d = 2.5;
  const vitamin_e::camera::Pinhole K = testImage().K;
  return [=](const Vector2d& uv) { return n.dot(K.ray(uv)) / d; };
}

}  // namespace

TEST(Nltgv, FlattensNoisyPlane) {
  std::vector<double> truth;
  FrameMesh mesh = noisyMesh(slantedPlane(), 0.02, 0.0, 11, &truth);
  ASSERT_GT(mesh.vertices.size(), 1500u);
  const double before = meanAbsError(mesh, truth, false);
  NltgvDenoiser denoiser;
  const NltgvStats stats = denoiser.denoise(&mesh, testImage().K);
  EXPECT_EQ(stats.warm_started, 0u);
  const double after = meanAbsError(mesh, truth, true);
  EXPECT_LT(after, 0.5 * before) << "before " << before << " after " << after;
}

TEST(Nltgv, RejectsOutliersOnPlane) {
  std::vector<double> truth;
  FrameMesh mesh = noisyMesh(slantedPlane(), 0.01, 0.05, 12, &truth);
  NltgvDenoiser denoiser;
  denoiser.denoise(&mesh, testImage().K);
  int bad = 0;
  for (std::size_t i = 0; i < truth.size(); ++i)
    if (std::abs(mesh.vertices[i].inv_depth - truth[i]) > 0.1 * truth[i]) ++bad;
  EXPECT_LT(bad, static_cast<int>(truth.size() / 100)) << "outliers survive";
}

TEST(Nltgv, KeepsStepEdgeSharp) {
  // Two fronto-parallel planes at 2 m (left) and 4 m (right), meshed across the step.
  const double cx = testImage().K.cx;
  auto step = [cx](const Vector2d& uv) { return uv.x() < cx ? 0.5 : 0.25; };
  std::vector<double> truth;
  FrameMesh mesh = noisyMesh(step, 0.02, 0.0, 13, &truth);
  const double before = meanAbsError(mesh, truth, false);
  NltgvDenoiser denoiser;
  denoiser.denoise(&mesh, testImage().K);
  EXPECT_LT(meanAbsError(mesh, truth, true), 0.5 * before);
  // Vertices next to the step stay on their own side: error far below the 0.25 jump.
  double worst_near_step = 0.0;
  for (std::size_t i = 0; i < truth.size(); ++i)
    if (std::abs(mesh.vertices[i].uv.x() - cx) < 15.0)
      worst_near_step = std::max(worst_near_step, std::abs(mesh.vertices[i].inv_depth - truth[i]));
  EXPECT_LT(worst_near_step, 0.05);
}

TEST(Nltgv, WarmStartByTrackId) {
  std::vector<double> truth;
  NltgvDenoiser denoiser;
  FrameMesh first = noisyMesh(slantedPlane(), 0.02, 0.0, 14, &truth);
  denoiser.denoise(&first, testImage().K);
  // The next frame re-observes the same tracks with fresh noise.
  FrameMesh second = noisyMesh(slantedPlane(), 0.02, 0.0, 15, &truth);
  const double before = meanAbsError(second, truth, false);
  const NltgvStats stats = denoiser.denoise(&second, testImage().K);
  EXPECT_EQ(stats.warm_started, second.vertices.size());
  EXPECT_EQ(stats.iterations, denoiser.config().warm_iterations);
  EXPECT_LT(meanAbsError(second, truth, true), 0.5 * before);
  denoiser.reset();
  FrameMesh third = noisyMesh(slantedPlane(), 0.02, 0.0, 16, &truth);
  EXPECT_EQ(denoiser.denoise(&third, testImage().K).warm_started, 0u);
}

TEST(Nltgv, SameResultInAnyMapUnit) {
  // A monocular map has an arbitrary unit: depths x k must give smoothed depths x k.
  std::vector<double> truth;
  const FrameMesh base = noisyMesh(slantedPlane(), 0.02, 0.03, 17, &truth);
  NltgvDenoiser reference;
  FrameMesh ref = base;
  reference.denoise(&ref, testImage().K);
  for (double k : {0.05, 20.0}) {
    FrameMesh scaled = base;
    for (auto& v : scaled.vertices) v.inv_depth = v.measured_inv_depth = v.measured_inv_depth / k;
    NltgvDenoiser denoiser;
    denoiser.denoise(&scaled, testImage().K);
    double worst = 0.0;
    for (std::size_t i = 0; i < ref.vertices.size(); ++i)
      worst = std::max(worst, std::abs(scaled.vertices[i].inv_depth * k / ref.vertices[i].inv_depth - 1.0));
    EXPECT_LT(worst, 1e-6) << "depth unit x" << k;
  }
}

TEST(Nltgv, ConfigValidation) {
  NltgvConfig cfg;
  cfg.lambda = 0.0;
  EXPECT_THROW(NltgvDenoiser{cfg}, std::invalid_argument);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
