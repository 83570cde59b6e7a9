// NLTGV2-L1 on the mesh graph, diagonally preconditioned primal-dual.
#include "vitamin_e/meshing/nltgv_denoiser.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace vitamin_e::meshing {

namespace {
void require(bool ok, const char* key, const std::string& what) {
  if (!ok) throw std::invalid_argument(std::string("nltgv.") + key + ": " + what);
}
std::uint64_t edgeKey(std::uint64_t a, std::uint64_t b) {
  return (a * 0x9E3779B97F4A7C15ULL) ^ (b + 0x632BE59BD9B4E019ULL + (a << 6) + (a >> 2));
}
double softThreshold(double x, double t) { return x > t ? x - t : (x < -t ? x + t : 0.0); }
double clamp1(double x) { return std::max(-1.0, std::min(1.0, x)); }
}  // namespace

void NltgvConfig::validate() const {
  require(alpha > 0.0, "alpha", "must be > 0");
  require(beta > 0.0, "beta", "must be > 0");
  require(lambda > 0.0, "lambda", "must be > 0");
  require(iterations >= 0, "iterations", "must be >= 0");
  require(warm_iterations >= 0, "warm_iterations", "must be >= 0");
  require(theta >= 0.0 && theta <= 1.0, "theta", "must be in [0, 1]");
  require(support_sigma >= 0.0, "support_sigma", "must be >= 0");
  require(min_support > 0.0 && min_support <= 1.0, "min_support", "must be in (0, 1]");
}

NltgvDenoiser::NltgvDenoiser(const NltgvConfig& config) : config_(config) { config_.validate(); }

void NltgvDenoiser::reset() {
  prev_vertices_.clear();
  prev_duals_.clear();
}

NltgvStats NltgvDenoiser::denoise(FrameMesh* mesh, const camera::Pinhole& K) {
  NltgvStats stats;
  auto& V = mesh->vertices;
  const int n = static_cast<int>(V.size());
  const auto undirected = mesh->edges();
  const int m = static_cast<int>(undirected.size());
  stats.edges = undirected.size();
  if (n == 0) return stats;
  const double a = config_.alpha, b = config_.beta, lam = config_.lambda;
  (void)a;

  // Primal: xi, wx, wy; their over-relaxed copies; measured z; steps.
  std::vector<double> z(n), xi(n), wx(n, 0.0), wy(n, 0.0), nx(n), ny(n);
  // Solve for inverse depths relative to their median: the L1 terms are
  // homogeneous but the primal steps and the data prox are absolute, so without
  // this a fixed iteration count would act differently in another map unit
  // (monocular maps have an arbitrary scale).
  double unit = 1.0;
  {
    std::vector<double> m;
    m.reserve(n);
    for (const auto& v : V)
      if (v.measured_inv_depth > 0.0 && std::isfinite(v.measured_inv_depth)) m.push_back(v.measured_inv_depth);
    if (!m.empty()) {
      std::nth_element(m.begin(), m.begin() + static_cast<std::ptrdiff_t>(m.size() / 2), m.end());
      unit = m[m.size() / 2];
    }
  }
  for (int i = 0; i < n; ++i) {
    z[i] = V[i].measured_inv_depth / unit;
    xi[i] = z[i];
    const Eigen::Vector2d xy = K.unproject(V[i].uv);
    nx[i] = xy.x();
    ny[i] = xy.y();
    if (config_.warm_start) {
      const auto it = prev_vertices_.find(V[i].id);
      if (it != prev_vertices_.end() && !config_.warm_start_primal) {
        ++stats.warm_started;
        continue;
      }
      if (it != prev_vertices_.end()) {
        xi[i] = z[i] * it->second.ratio;
        wx[i] = it->second.wx * xi[i];
        wy[i] = it->second.wy * xi[i];
        ++stats.warm_started;
      }
    }
  }
  // Adjacency (undirected) for the median filter and the gradient initialisation.
  std::vector<int> deg(n + 1, 0), adj(2 * undirected.size());
  for (const auto& e : undirected) ++deg[e.first + 1], ++deg[e.second + 1];
  for (int i = 0; i < n; ++i) deg[i + 1] += deg[i];
  {
    std::vector<int> fill(deg.begin(), deg.end() - 1);
    for (const auto& e : undirected) adj[fill[e.first]++] = e.second, adj[fill[e.second]++] = e.first;
  }
  std::vector<double> zmed(n), ring;
  for (int i = 0; i < n; ++i) {
    ring.assign(1, z[i]);
    for (int k = deg[i]; k < deg[i + 1]; ++k) ring.push_back(z[adj[k]]);
    std::nth_element(ring.begin(), ring.begin() + static_cast<std::ptrdiff_t>(ring.size() / 2), ring.end());
    zmed[i] = ring[ring.size() / 2];
  }
  // 1-ring least-squares gradient of the median-filtered data (per normalized coordinate).
  std::vector<double> gx(n, 0.0), gy(n, 0.0);
  for (int i = 0; i < n; ++i) {
    Eigen::Matrix2d A = Eigen::Matrix2d::Zero();
    Eigen::Vector2d rhs = Eigen::Vector2d::Zero();
    for (int k = deg[i]; k < deg[i + 1]; ++k) {
      const int j = adj[k];
      const Eigen::Vector2d d(nx[j] - nx[i], ny[j] - ny[i]);
      A += d * d.transpose();
      rhs += d * (zmed[j] - zmed[i]);
    }
    if (deg[i + 1] - deg[i] >= 2 && A.determinant() > 1e-16) {
      const Eigen::Vector2d g = A.ldlt().solve(rhs);
      gx[i] = g.x();
      gy[i] = g.y();
    }
  }
  // Support weight: how badly each end's local plane predicts the other end.
  auto support = [&](int i, int j) {
    if (config_.support_sigma <= 0.0) return a;
    const double dxn = nx[j] - nx[i], dyn = ny[j] - ny[i];
    const double ri = std::abs(zmed[j] - zmed[i] - gx[i] * dxn - gy[i] * dyn);
    const double rj = std::abs(zmed[i] - zmed[j] + gx[j] * dxn + gy[j] * dyn);
    const double r = 0.5 * (ri + rj) / (std::max(zmed[i], zmed[j]) * config_.support_sigma);
    return a * std::max(config_.min_support, std::exp(-r * r));
  };
  for (int i = 0; i < n; ++i)
    if (wx[i] == 0.0 && wy[i] == 0.0) wx[i] = gx[i], wy[i] = gy[i];  // cold start
  std::vector<int> ei(m), ej(m);
  std::vector<double> ae(m);
  std::vector<double> dx(m), dy(m), p0(m, 0.0), p1(m, 0.0), p2(m, 0.0), s0(m);
  std::vector<double> tau_xi(n, 0.0), tau_wx(n, 0.0), tau_wy(n, 0.0);
  for (int k = 0; k < m; ++k) {
    // Orient every edge by track id so that warm-started duals keep their sign.
    const auto& ue = undirected[k];
    const bool flip = V[ue.first].id > V[ue.second].id;
    const int i = flip ? ue.second : ue.first;
    const int j = flip ? ue.first : ue.second;
    ei[k] = i;
    ej[k] = j;
    dx[k] = nx[i] - nx[j];
    dy[k] = ny[i] - ny[j];
    ae[k] = support(i, j);
    s0[k] = 1.0 / (ae[k] * (2.0 + std::abs(dx[k]) + std::abs(dy[k])));
    tau_xi[i] += ae[k];
    tau_xi[j] += ae[k];
    tau_wx[i] += 0.5 * ae[k] * std::abs(dx[k]) + b;
    tau_wy[i] += 0.5 * ae[k] * std::abs(dy[k]) + b;
    tau_wx[j] += 0.5 * ae[k] * std::abs(dx[k]) + b;
    tau_wy[j] += 0.5 * ae[k] * std::abs(dy[k]) + b;
    if (config_.warm_start && !prev_duals_.empty()) {
      const auto it = prev_duals_.find(edgeKey(V[i].id, V[j].id));
      if (it != prev_duals_.end()) {
        p0[k] = it->second.x();
        p1[k] = it->second.y();
        p2[k] = it->second.z();
      }
    }
  }
  for (int i = 0; i < n; ++i) {
    tau_xi[i] = tau_xi[i] > 0.0 ? 1.0 / tau_xi[i] : 0.0;
    tau_wx[i] = tau_wx[i] > 0.0 ? 1.0 / tau_wx[i] : 0.0;
    tau_wy[i] = tau_wy[i] > 0.0 ? 1.0 / tau_wy[i] : 0.0;
  }
  const double s12 = 1.0 / (2.0 * b);
  const bool warm = stats.warm_started * 2 > static_cast<std::size_t>(n);
  stats.iterations = warm ? config_.warm_iterations : config_.iterations;

  std::vector<double> bxi = xi, bwx = wx, bwy = wy;
  std::vector<double> gxi(n), gwx(n), gwy(n);
  for (int it = 0; it < stats.iterations; ++it) {
    // Dual ascent + projection onto the unit box; accumulate K^T p on the fly.
    std::fill(gxi.begin(), gxi.end(), 0.0);
    std::fill(gwx.begin(), gwx.end(), 0.0);
    std::fill(gwy.begin(), gwy.end(), 0.0);
    for (int k = 0; k < m; ++k) {
      const int i = ei[k], j = ej[k];
      const double a = ae[k];
      const double r0 = a * (bxi[i] - bxi[j] - 0.5 * ((bwx[i] + bwx[j]) * dx[k] + (bwy[i] + bwy[j]) * dy[k]));
      const double q0 = clamp1(p0[k] + s0[k] * r0);
      const double q1 = clamp1(p1[k] + s12 * b * (bwx[i] - bwx[j]));
      const double q2 = clamp1(p2[k] + s12 * b * (bwy[i] - bwy[j]));
      p0[k] = q0;
      p1[k] = q1;
      p2[k] = q2;
      gxi[i] += a * q0;
      gxi[j] -= a * q0;
      const double hx = 0.5 * a * q0 * dx[k], hy = 0.5 * a * q0 * dy[k];
      gwx[i] += b * q1 - hx;
      gwy[i] += b * q2 - hy;
      gwx[j] -= b * q1 + hx;
      gwy[j] -= b * q2 + hy;
    }
    // Primal descent, prox of the L1 data term, over-relaxation.
    for (int i = 0; i < n; ++i) {
      const double x_old = xi[i], wx_old = wx[i], wy_old = wy[i];
      const double x_hat = xi[i] - tau_xi[i] * gxi[i];
      xi[i] = z[i] + softThreshold(x_hat - z[i], tau_xi[i] * lam);
      wx[i] -= tau_wx[i] * gwx[i];
      wy[i] -= tau_wy[i] * gwy[i];
      bxi[i] = xi[i] + config_.theta * (xi[i] - x_old);
      bwx[i] = wx[i] + config_.theta * (wx[i] - wx_old);
      bwy[i] = wy[i] + config_.theta * (wy[i] - wy_old);
    }
  }

  for (int i = 0; i < n; ++i)
    if (xi[i] > 0.0 && std::isfinite(xi[i])) V[i].inv_depth = xi[i] * unit;
  if (config_.warm_start) {
    prev_vertices_.clear();
    prev_vertices_.reserve(n);
    for (int i = 0; i < n; ++i) {
      if (!(xi[i] > 0.0) || !(z[i] > 0.0)) continue;
      prev_vertices_[V[i].id] = {xi[i] / z[i], wx[i] / xi[i], wy[i] / xi[i]};
    }
    prev_duals_.clear();
    prev_duals_.reserve(m);
    for (int k = 0; k < m; ++k) prev_duals_[edgeKey(V[ei[k]].id, V[ej[k]].id)] = {p0[k], p1[k], p2[k]};
  }
  return stats;
}

}  // namespace vitamin_e::meshing
