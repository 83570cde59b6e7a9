// NLTGV2-L1 on the mesh graph, diagonally preconditioned primal-dual.
#include "vitamin_e/meshing/nltgv_denoiser.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "vitamin_e/common/lanes.h"

namespace vitamin_e::meshing {

using common::Lanes;

namespace {
void require(bool ok, const char* key, const std::string& what) {
  if (!ok) throw std::invalid_argument(std::string("nltgv.") + key + ": " + what);
}
std::uint64_t edgeKey(std::uint64_t a, std::uint64_t b) {
  return (a * 0x9E3779B97F4A7C15ULL) ^ (b + 0x632BE59BD9B4E019ULL + (a << 6) + (a >> 2));
}
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
      const VertexState* prev = prev_vertices_.find(V[i].id);
      if (prev && !config_.warm_start_primal) {
        ++stats.warm_started;
        continue;
      }
      if (prev) {
        xi[i] = z[i] * prev->ratio;
        wx[i] = prev->wx * xi[i];
        wy[i] = prev->wy * xi[i];
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
  // The iteration works on packed (xi, wx, wy, 0) vertex states and (p0, p1, p2, 0) edge duals
  // in float: one 4-lane operation per edge and term instead of three scalar ones. The
  // inverse depths are relative to their median (about 1), far from float's precision.
  // Edges in rounds that share no vertex (a greedy edge colouring): consecutive edges then
  // update different vertices, so the loop does not wait on its own last store.
  std::vector<int> order(m);
  {
    std::vector<std::uint64_t> used(n, 0);  // colours taken at each vertex
    std::vector<int> colour(m), count(65, 0);
    for (int k = 0; k < m; ++k) {
      const int u = undirected[k].first, v = undirected[k].second;
      const std::uint64_t taken = used[u] | used[v];
      const int c = taken == ~std::uint64_t{0} ? 64 : __builtin_ctzll(~taken);
      if (c < 64) used[u] |= std::uint64_t{1} << c, used[v] |= std::uint64_t{1} << c;
      colour[k] = c;
      ++count[c];
    }
    std::vector<int> start(66, 0);
    for (int c = 0; c < 65; ++c) start[c + 1] = start[c] + count[c];
    for (int k = 0; k < m; ++k) order[start[colour[k]]++] = k;
  }
  struct Edge {
    Lanes weights;  // (alpha_ij, beta, beta, 0): the duals' weights in K^T p
    Lanes half_d;   // (0, dx / 2, dy / 2, 0): the mean gradient's lever
    Lanes lever;    // (1, -dx / 2, -dy / 2, 0): first-order residual from (xi_i - xi_j, w_i + w_j)
    Lanes step;     // dual steps: the first-order term's in lane 0, 1 / (2 beta) times beta in 1, 2
    int i, j;
  };
  std::vector<Edge> edges(m);
  std::vector<Lanes> dual(m, Lanes::all(0.0f));
  std::vector<double> tau_xi(n, 0.0), tau_wx(n, 0.0), tau_wy(n, 0.0);
  const float fb = static_cast<float>(b);
  for (int k = 0; k < m; ++k) {
    // Orient every edge by track id so that warm-started duals keep their sign.
    const auto& ue = undirected[order[k]];
    const bool flip = V[ue.first].id > V[ue.second].id;
    const int i = flip ? ue.second : ue.first;
    const int j = flip ? ue.first : ue.second;
    const double dx = nx[i] - nx[j], dy = ny[i] - ny[j];
    const double w = support(i, j);
    const float hx = static_cast<float>(0.5 * dx), hy = static_cast<float>(0.5 * dy);
    Edge& e = edges[k];
    e.i = i;
    e.j = j;
    e.weights = Lanes::of(static_cast<float>(w), fb, fb, 0.0f);
    e.half_d = Lanes::of(0.0f, hx, hy, 0.0f);
    e.lever = Lanes::of(1.0f, -hx, -hy, 0.0f);
    e.step = Lanes::of(static_cast<float>(1.0 / (2.0 + std::abs(dx) + std::abs(dy))), 0.5f, 0.5f, 0.0f);
    tau_xi[i] += w;
    tau_xi[j] += w;
    tau_wx[i] += 0.5 * w * std::abs(dx) + b;
    tau_wy[i] += 0.5 * w * std::abs(dy) + b;
    tau_wx[j] += 0.5 * w * std::abs(dx) + b;
    tau_wy[j] += 0.5 * w * std::abs(dy) + b;
    if (config_.warm_start && !prev_duals_.empty()) {
      if (const Eigen::Vector3f* p = prev_duals_.find(edgeKey(V[i].id, V[j].id)))
        dual[k] = Lanes::of(p->x(), p->y(), p->z(), 0.0f);
    }
  }
  const auto inverse = [](double t) { return static_cast<float>(t > 0.0 ? 1.0 / t : 0.0); };
  // The data term acts on xi only: its measurement and threshold sit in lane 0, and zeros in the
  // other lanes leave the gradients to the plain descent step.
  std::vector<Lanes> x(n), tau(n), bar(n), grad(n), data(n), threshold(n);
  for (int i = 0; i < n; ++i) {
    x[i] = Lanes::of(static_cast<float>(xi[i]), static_cast<float>(wx[i]), static_cast<float>(wy[i]), 0.0f);
    tau[i] = Lanes::of(inverse(tau_xi[i]), inverse(tau_wx[i]), inverse(tau_wy[i]), 0.0f);
    data[i] = Lanes::of(static_cast<float>(z[i]), 0.0f, 0.0f, 0.0f);
    threshold[i] = Lanes::of(inverse(tau_xi[i]) * static_cast<float>(lam), 0.0f, 0.0f, 0.0f);
  }
  const Lanes one = Lanes::all(1.0f);
  const Lanes theta = Lanes::all(static_cast<float>(config_.theta));
  const bool warm = stats.warm_started * 2 > static_cast<std::size_t>(n);
  stats.iterations = warm ? config_.warm_iterations : config_.iterations;

  bar = x;
  std::fill(grad.begin(), grad.end(), Lanes::all(0.0f));  // the primal step zeroes it after use
  for (int it = 0; it < stats.iterations; ++it) {
    // Dual ascent + projection onto the unit box; K^T p accumulated on the fly.
    for (int k = 0; k < m; ++k) {
      const Edge& e = edges[k];
      const Lanes bi = bar[e.i], bj = bar[e.j];
      const Lanes diff = bi - bj;
      // (xi_i - xi_j, w_i + w_j) . lever: the first-order residual, in every lane.
      const Lanes r0 = ((bi + bj).withFirst(diff) * e.lever).sumInAll();
      const Lanes q = (dual[k] + diff.withFirst(r0) * e.step).clamp(one);
      dual[k] = q;
      const Lanes weighted = q * e.weights;
      const Lanes lever_term = weighted.broadcastFirst() * e.half_d;
      grad[e.i] += weighted - lever_term;
      grad[e.j] -= weighted + lever_term;
    }
    // Primal descent, prox of the L1 data term (soft threshold towards the data), over-relaxation.
    for (int i = 0; i < n; ++i) {
      const Lanes x_old = x[i];
      const Lanes x_hat = x_old - tau[i] * grad[i];
      grad[i] = Lanes::all(0.0f);
      const Lanes x_new = x_hat - (x_hat - data[i]).clamp(threshold[i]);
      x[i] = x_new;
      bar[i] = x_new + theta * (x_new - x_old);
    }
  }
  for (int i = 0; i < n; ++i) {
    xi[i] = x[i][0];
    wx[i] = x[i][1];
    wy[i] = x[i][2];
  }

  for (int i = 0; i < n; ++i)
    if (xi[i] > 0.0 && std::isfinite(xi[i])) V[i].inv_depth = xi[i] * unit;
  if (config_.warm_start) {
    prev_vertices_.reset(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) {
      if (!(xi[i] > 0.0) || !(z[i] > 0.0)) continue;
      prev_vertices_.set(V[i].id, {xi[i] / z[i], wx[i] / xi[i], wy[i] / xi[i]});
    }
    prev_duals_.reset(static_cast<std::size_t>(m));
    for (int k = 0; k < m; ++k)
      prev_duals_.set(edgeKey(V[edges[k].i].id, V[edges[k].j].id), Eigen::Vector3f(dual[k][0], dual[k][1], dual[k][2]));
  }
  return stats;
}

}  // namespace vitamin_e::meshing
