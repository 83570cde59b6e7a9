// Incremental Bowyer-Watson Delaunay triangulation with walking point location.
#include "vitamin_e/meshing/delaunay.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>

namespace vitamin_e::meshing {

double orient2d(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c) {
  return (b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x());
}

double inCircle(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c,
                const Eigen::Vector2d& d) {
  const double adx = a.x() - d.x(), ady = a.y() - d.y();
  const double bdx = b.x() - d.x(), bdy = b.y() - d.y();
  const double cdx = c.x() - d.x(), cdy = c.y() - d.y();
  return (adx * adx + ady * ady) * (bdx * cdy - cdx * bdy) + (bdx * bdx + bdy * bdy) * (cdx * ady - adx * cdy) +
         (cdx * cdx + cdy * cdy) * (adx * bdy - bdx * ady);
}

namespace {

struct Tri {
  std::array<int, 3> v;  // counter-clockwise vertices
  std::array<int, 3> n;  // n[i]: neighbour across the edge opposite v[i] (-1: none)
};

class Triangulator {
 public:
  explicit Triangulator(std::vector<Eigen::Vector2d> pts) : p_(std::move(pts)) {}

  void run(const std::vector<int>& order, int super0) {
    tris_.push_back({{super0, super0 + 1, super0 + 2}, {-1, -1, -1}});
    mark_.push_back(0);
    for (int idx : order) insert(idx);
  }
  const std::vector<Tri>& tris() const { return tris_; }
  const std::vector<int>& freeList() const { return free_; }
  bool alive(int t) const { return mark_[t] != kDead; }

 private:
  static constexpr int kDead = -1;

  bool inside(int t, const Eigen::Vector2d& q) const {
    const Tri& tr = tris_[t];
    return inCircle(p_[tr.v[0]], p_[tr.v[1]], p_[tr.v[2]], q) > 0.0;
  }

  int locate(const Eigen::Vector2d& q) {
    int t = last_;
    const std::size_t max_steps = 4 * tris_.size() + 16;
    for (std::size_t step = 0; step < max_steps; ++step) {
      const Tri& tr = tris_[t];
      bool moved = false;
      for (int k = 0; k < 3; ++k) {
        const int i = (k + static_cast<int>(step)) % 3;  // rotate the start edge: avoids cycling
        if (orient2d(p_[tr.v[(i + 1) % 3]], p_[tr.v[(i + 2) % 3]], q) < 0.0 && tr.n[i] >= 0) {
          t = tr.n[i];
          moved = true;
          break;
        }
      }
      if (!moved) return t;
    }
    for (int s = 0; s < static_cast<int>(tris_.size()); ++s) {  // fallback: exhaustive search
      if (!alive(s)) continue;
      const Tri& tr = tris_[s];
      if (orient2d(p_[tr.v[0]], p_[tr.v[1]], q) >= 0.0 && orient2d(p_[tr.v[1]], p_[tr.v[2]], q) >= 0.0 &&
          orient2d(p_[tr.v[2]], p_[tr.v[0]], q) >= 0.0)
        return s;
    }
    return -1;
  }

  void insert(int pi) {
    const Eigen::Vector2d& q = p_[pi];
    const int t0 = locate(q);
    if (t0 < 0) return;
    for (int k = 0; k < 3; ++k)
      if (p_[tris_[t0].v[k]] == q) return;  // duplicate point
    ++stamp_;
    const int bad = 2 * stamp_, good = 2 * stamp_ + 1;
    bad_.clear();
    bad_.push_back(t0);
    mark_[t0] = bad;
    for (std::size_t k = 0; k < bad_.size(); ++k) {
      const Tri& tr = tris_[bad_[k]];
      for (int nb : tr.n) {
        if (nb < 0 || mark_[nb] == bad || mark_[nb] == good) continue;
        if (inside(nb, q)) {
          mark_[nb] = bad;
          bad_.push_back(nb);
        } else {
          mark_[nb] = good;
        }
      }
    }
    // Boundary of the cavity, each edge with its outer neighbour.
    edges_.clear();
    for (int t : bad_) {
      const Tri& tr = tris_[t];
      for (int i = 0; i < 3; ++i) {
        const int nb = tr.n[i];
        if (nb >= 0 && mark_[nb] == bad) continue;
        edges_.push_back({tr.v[(i + 1) % 3], tr.v[(i + 2) % 3], nb, t});
      }
    }
    for (int t : bad_) {
      mark_[t] = kDead;
      free_.push_back(t);
    }
    created_.clear();
    for (const auto& e : edges_) {
      int slot;
      if (!free_.empty()) {
        slot = free_.back();
        free_.pop_back();
      } else {
        slot = static_cast<int>(tris_.size());
        tris_.push_back({});
        mark_.push_back(0);
      }
      mark_[slot] = 0;
      tris_[slot] = {{e.a, e.b, pi}, {-1, -1, e.outer}};
      if (e.outer >= 0) {
        Tri& o = tris_[e.outer];
        for (int k = 0; k < 3; ++k)
          if (o.n[k] == e.from && o.v[(k + 1) % 3] == e.b && o.v[(k + 2) % 3] == e.a) o.n[k] = slot;
      }
      created_.push_back(slot);
    }
    // Link the fan: across (b, p) is the new triangle starting at b; across (p, a) the one ending at a.
    for (int s : created_) {
      Tri& tr = tris_[s];
      for (int o : created_) {
        if (tris_[o].v[0] == tr.v[1]) tr.n[0] = o;
        if (tris_[o].v[1] == tr.v[0]) tr.n[1] = o;
      }
    }
    last_ = created_.front();
  }

  std::vector<Eigen::Vector2d> p_;
  std::vector<Tri> tris_;
  std::vector<int> mark_, free_, bad_, created_;
  struct EdgeRec {
    int a, b, outer, from;
  };
  std::vector<EdgeRec> edges_;
  int stamp_ = 0;
  int last_ = 0;
};

}  // namespace

std::vector<Eigen::Vector3i> delaunayTriangulate(const std::vector<Eigen::Vector2d>& points) {
  const int n = static_cast<int>(points.size());
  std::vector<Eigen::Vector3i> out;
  if (n < 3) return out;
  Eigen::Vector2d lo = points[0], hi = points[0];
  for (const auto& p : points) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const double extent = std::max({hi.x() - lo.x(), hi.y() - lo.y(), 1e-12});
  // Normalise to [0, 1]^2 for conditioning; append a far super-triangle.
  std::vector<Eigen::Vector2d> pts(n + 3);
  for (int i = 0; i < n; ++i) pts[i] = (points[i] - lo) / extent;
  constexpr double kFar = 1e4;
  pts[n] = {-kFar, -kFar};
  pts[n + 1] = {kFar, -kFar};
  pts[n + 2] = {0.5, kFar};

  // Insertion order: cells of a grid visited in snake order.
  const int g = std::max(1, static_cast<int>(std::sqrt(n / 4.0)));
  std::vector<long> key(n);
  for (int i = 0; i < n; ++i) {
    const int cx = std::min(g - 1, static_cast<int>(pts[i].x() * g));
    const int cy = std::min(g - 1, static_cast<int>(pts[i].y() * g));
    key[i] = static_cast<long>(cy) * g + ((cy & 1) ? (g - 1 - cx) : cx);
  }
  std::vector<int> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return key[a] < key[b]; });

  Triangulator tri(std::move(pts));
  tri.run(order, n);
  const auto& tris = tri.tris();
  out.reserve(2 * static_cast<std::size_t>(n));
  for (int t = 0; t < static_cast<int>(tris.size()); ++t) {
    if (!tri.alive(t)) continue;
    const auto& v = tris[t].v;
    if (v[0] >= n || v[1] >= n || v[2] >= n) continue;
    out.emplace_back(v[0], v[1], v[2]);
  }
  return out;
}

}  // namespace vitamin_e::meshing
