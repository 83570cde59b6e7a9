#include "vitamin_e/pipeline/map_reuse.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>
#include <vector>

namespace vitamin_e::pipeline {

namespace {

// Tracks bucketed by their pinhole pixel position (a counting sort into square
// cells over the image; tracks outside it are left out).
class TrackGrid {
 public:
  TrackGrid(int width, int height, double cell)
      : inv_cell_(1.0 / cell), w_(static_cast<int>(width / cell) + 1), h_(static_cast<int>(height / cell) + 1) {}
  void build(const std::vector<Eigen::Vector2d>& px) {
    start_.assign(static_cast<std::size_t>(w_ * h_) + 1, 0);
    std::vector<int> cell_of(px.size());
    for (std::size_t i = 0; i < px.size(); ++i) {
      cell_of[i] = index(cellOf(px[i].x()), cellOf(px[i].y()));
      if (cell_of[i] >= 0) ++start_[cell_of[i] + 1];
    }
    for (std::size_t c = 1; c < start_.size(); ++c) start_[c] += start_[c - 1];
    items_.resize(start_.back());
    std::vector<int> fill(start_.begin(), start_.end() - 1);
    for (std::size_t i = 0; i < px.size(); ++i) {
      if (cell_of[i] >= 0) items_[fill[cell_of[i]]++] = static_cast<int>(i);
    }
  }
  template <typename F>
  void forNear(const Eigen::Vector2d& px, F&& f) const {
    const int cx = cellOf(px.x()), cy = cellOf(px.y());
    for (int y = cy - 1; y <= cy + 1; ++y) {
      for (int x = cx - 1; x <= cx + 1; ++x) {
        const int c = index(x, y);
        if (c < 0) continue;
        for (int k = start_[c]; k < start_[c + 1]; ++k) f(items_[k]);
      }
    }
  }

 private:
  int cellOf(double v) const { return static_cast<int>(std::floor(v * inv_cell_)); }
  int index(int x, int y) const { return x >= 0 && y >= 0 && x < w_ && y < h_ ? y * w_ + x : -1; }
  double inv_cell_;
  int w_, h_;
  std::vector<int> start_;  // per cell, its first entry in items_
  std::vector<int> items_;
};

// Smallest depth of the mapped tracks per coarse image cell.
class DepthGrid {
 public:
  DepthGrid(int width, int height, int cell)
      : cell_(cell),
        w_(width / cell + 1),
        h_(height / cell + 1),
        depth_(static_cast<std::size_t>(w_ * h_), std::numeric_limits<double>::infinity()) {}
  void add(const Eigen::Vector2d& px, double z) {
    const int i = index(px);
    if (i >= 0) depth_[i] = std::min(depth_[i], z);
  }
  double at(const Eigen::Vector2d& px) const {
    const int i = index(px);
    return i >= 0 ? depth_[i] : std::numeric_limits<double>::infinity();
  }

 private:
  int index(const Eigen::Vector2d& px) const {
    const int x = static_cast<int>(std::floor(px.x() / cell_)), y = static_cast<int>(std::floor(px.y() / cell_));
    return x >= 0 && y >= 0 && x < w_ && y < h_ ? y * w_ + x : -1;
  }
  int cell_, w_, h_;
  std::vector<double> depth_;
};

struct Claim {
  double d2 = std::numeric_limits<double>::infinity();
  bool dormant = false;
  std::uint64_t landmark_id = 0;  // active landmark (relabel)
  std::size_t dormant_index = 0;  // dormant landmark (revive)
};

}  // namespace

MapReuse::MapReuse(const SystemConfig& config, const camera::Camera& camera)
    : radius_px_(config.reuse_radius_px),
      occlusion_ratio_(config.reuse_occlusion_ratio),
      dormant_per_frame_(static_cast<std::size_t>(config.reuse_dormant_per_frame)),
      camera_(camera) {}

std::vector<Reassociation> MapReuse::associate(const FrameContext& frame, const Eigen::Isometry3d& T_w_c,
                                               double scene_depth, const map::Map& map, bool all_dormant) {
  const double radius = radius_px_;
  const std::vector<FrameTrack>& tracks = frame.tracks;
  const camera::Camera& camera = camera_;
  if (!(radius > 0.0) || tracks.empty()) return {};
  // Per track, whether it carries a map point (the map as it is: nothing changes it here).
  std::vector<bool> mapped(tracks.size());
  const Eigen::Isometry3d T_c_w = T_w_c.inverse();
  const camera::Pinhole& K = camera.pinhole();
  TrackGrid grid(camera.width(), camera.height(), std::max(radius, 1.0));
  DepthGrid depth(camera.width(), camera.height(), 24);
  std::vector<Eigen::Vector2d> track_px(tracks.size());
  for (std::size_t i = 0; i < tracks.size(); ++i) {
    track_px[i] = K.project(tracks[i].xy);
    const map::Landmark* l = map.landmark(tracks[i].id);
    mapped[i] = l != nullptr;
    if (l) {
      const double z = (T_c_w * l->p_w).z();
      if (z > 0.0) depth.add(track_px[i], z);
    }
  }
  grid.build(track_px);
  const double r2 = radius * radius;
  const double min_depth = 1e-3 * scene_depth;
  std::vector<Claim> claims(tracks.size());
  auto consider = [&](const Eigen::Vector3d& p_w, std::int8_t polarity, const Claim& what) {
    const Eigen::Vector3d p_c = T_c_w * p_w;
    if (p_c.z() <= min_depth) return;
    const Eigen::Vector2d px = K.project(p_c.hnormalized());
    if (px.x() < 0 || px.y() < 0 || px.x() >= camera.width() || px.y() >= camera.height()) return;
    if (p_c.z() > occlusion_ratio_ * depth.at(px)) return;
    int nearest = -1;
    double best = std::numeric_limits<double>::infinity();
    grid.forNear(px, [&](int i) {
      const double d2 = (track_px[i] - px).squaredNorm();
      if (d2 < best) {
        best = d2;
        nearest = i;
      }
    });
    // The nearest track must be unmapped, of the same curvature sign, and close.
    if (nearest < 0 || best > r2 || mapped[nearest]) return;
    if (polarity != 0 && tracks[nearest].polarity != polarity) return;
    Claim& c = claims[nearest];
    if (best < c.d2) {
      c = what;
      c.d2 = best;
    }
  };
  // Landmarks whose track ended: not seen in this frame (the seen ones are marked before).
  for (const auto& kv : map.landmarks()) {
    if (kv.second.last_seen_frame == frame.frame_index) continue;
    Claim c;
    c.landmark_id = kv.first;
    consider(kv.second.p_w, kv.second.polarity, c);
  }
  // Dormant landmarks, a bounded slice per frame in round robin: a new track
  // stays unmapped until the next keyframe, so it is met by several slices.
  const auto& dormant = map.dormant();
  const std::size_t budget = all_dormant ? dormant.size() : std::min<std::size_t>(dormant.size(), dormant_per_frame_);
  const std::uint64_t dropped = map.dormantDropped();
  std::size_t start = dormant_cursor_ > dropped ? static_cast<std::size_t>(dormant_cursor_ - dropped) : 0;
  if (start >= dormant.size()) start = 0;
  for (std::size_t n = 0; n < budget; ++n) {
    const std::size_t k = (start + n) % dormant.size();
    if (dormant[k].revived) continue;
    Claim c;
    c.dormant = true;
    c.dormant_index = k;
    consider(dormant[k].p_w, dormant[k].polarity, c);
  }
  if (!dormant.empty()) dormant_cursor_ = dropped + (start + budget) % dormant.size();
  // One track per landmark: a landmark claimed by two tracks goes to the nearer.
  std::unordered_map<std::uint64_t, std::size_t> winner;  // landmark key -> track index
  auto key_of = [](const Claim& c) { return c.dormant ? (c.dormant_index << 1 | 1) : (c.landmark_id << 1); };
  for (std::size_t i = 0; i < claims.size(); ++i) {
    if (!std::isfinite(claims[i].d2)) continue;
    auto [it, inserted] = winner.emplace(key_of(claims[i]), i);
    if (!inserted && claims[i].d2 < claims[it->second].d2) it->second = i;
  }
  std::vector<Reassociation> out;
  out.reserve(winner.size());
  for (const auto& kv : winner) {
    const Claim& c = claims[kv.second];
    const FrameTrack& t = tracks[kv.second];
    Reassociation r;
    r.track_id = t.id;
    r.track_polarity = t.polarity;
    r.frame_index = frame.frame_index;
    r.dormant = c.dormant;
    r.landmark_id = c.landmark_id;
    r.dormant_index = c.dormant_index;
    out.push_back(r);
  }
  return out;
}

}  // namespace vitamin_e::pipeline
