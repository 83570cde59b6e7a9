#pragma once
// Ground truth for bench_fusion_dense: the render's scene (room seen from inside,
// axis-aligned boxes seen from outside) read from scene.json, ray casting, and
// point-to-surface distance. Header-only, bench use only.
#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace dense_bench {

struct Box {
  Eigen::Vector3d lo, hi;
};

struct Scene {
  Box room;
  std::vector<Box> boxes;
  Eigen::Matrix3d K = Eigen::Matrix3d::Identity();
  std::vector<double> dist;  // radtan k1 k2 p1 p2
  int width = 0, height = 0;
};

inline Eigen::Vector3d vec3(const cv::FileNode& n) {
  if (n.size() != 3) throw std::runtime_error("scene.json: expected 3 numbers");
  return {static_cast<double>(n[0]), static_cast<double>(n[1]), static_cast<double>(n[2])};
}

inline Scene loadScene(const std::string& path) {
  cv::FileStorage fs(path, cv::FileStorage::READ | cv::FileStorage::FORMAT_JSON);
  if (!fs.isOpened()) throw std::runtime_error("cannot read " + path);
  Scene s;
  s.room = {vec3(fs["room"]["min"]), vec3(fs["room"]["max"])};
  for (const auto& b : fs["boxes"]) s.boxes.push_back({vec3(b["min"]), vec3(b["max"])});
  const cv::FileNode cam = fs["camera"];
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) s.K(r, c) = static_cast<double>(cam["K"][r][c]);
  for (const auto& d : cam["dist_radtan"]) s.dist.push_back(static_cast<double>(d));
  s.width = static_cast<int>(cam["width"]);
  s.height = static_cast<int>(cam["height"]);
  return s;
}

// Entry distance of ray o + t d into box (slab test); +inf if missed or behind.
inline double rayBoxEntry(const Box& b, const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
  double t0 = 0.0, t1 = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 3; ++k) {
    if (std::abs(d[k]) < 1e-15) {
      if (o[k] < b.lo[k] || o[k] > b.hi[k]) return std::numeric_limits<double>::infinity();
      continue;
    }
    double a = (b.lo[k] - o[k]) / d[k], c = (b.hi[k] - o[k]) / d[k];
    if (a > c) std::swap(a, c);
    t0 = std::max(t0, a);
    t1 = std::min(t1, c);
  }
  return (t0 <= t1 && t0 > 1e-9) ? t0 : std::numeric_limits<double>::infinity();
}

// Exit distance of a ray starting inside the room.
inline double rayRoomExit(const Box& b, const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
  double t = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 3; ++k) {
    if (d[k] > 1e-15) t = std::min(t, (b.hi[k] - o[k]) / d[k]);
    if (d[k] < -1e-15) t = std::min(t, (b.lo[k] - o[k]) / d[k]);
  }
  return t;
}

// Ray parameter of the first surface hit (d need not be unit).
inline double rayCast(const Scene& s, const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
  double t = rayRoomExit(s.room, o, d);
  for (const auto& b : s.boxes) t = std::min(t, rayBoxEntry(b, o, d));
  return t;
}

// Distance from p to the surface of an axis-aligned box (inside or outside).
inline double boxSurfaceDistance(const Box& b, const Eigen::Vector3d& p) {
  const Eigen::Vector3d q = p.cwiseMax(b.lo).cwiseMin(b.hi);
  const double outside = (p - q).norm();
  if (outside > 0.0) return outside;
  const Eigen::Vector3d a = p - b.lo, c = b.hi - p;
  return std::min(a.minCoeff(), c.minCoeff());
}

inline double surfaceDistance(const Scene& s, const Eigen::Vector3d& p) {
  double d = boxSurfaceDistance(s.room, p);
  for (const auto& b : s.boxes) d = std::min(d, boxSurfaceDistance(b, p));
  return d;
}

// Closest point on triangle abc to p (Ericson, Real-Time Collision Detection, 5.1.5).
inline Eigen::Vector3d closestOnTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                         const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + ab * (d1 / (d1 - d3));
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + ac * (d2 / (d2 - d6));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  const double den = 1.0 / (va + vb + vc);
  return a + ab * (vb * den) + ac * (vc * den);
}

}  // namespace dense_bench
