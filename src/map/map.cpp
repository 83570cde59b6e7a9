#include "vitamin_e/map/map.h"

#include <cmath>
#include <stdexcept>
#include <algorithm>

namespace vitamin_e::map {

void MapConfig::validate() const {
  if (max_keyframes < 2) throw std::invalid_argument("map.max_keyframes must be >= 2");
  if (!(archive_voxel_m >= 0.0)) throw std::invalid_argument("map.archive_voxel_m must be >= 0");
  if (min_observations_to_archive < 1) throw std::invalid_argument("map.min_observations_to_archive must be >= 1");
  if (max_archive_points < 2) throw std::invalid_argument("map.max_archive_points must be >= 2");
}

namespace {
// Voxel index of p packed into 64 bits (21 bits per axis, clamped far out).
std::uint64_t voxelKey(const Eigen::Vector3d& p, double voxel) {
  constexpr std::int64_t kHalf = 1 << 20;
  std::uint64_t key = 0;
  for (int k = 0; k < 3; ++k) {
    const double i = std::floor(p[k] / voxel);
    const std::int64_t c = static_cast<std::int64_t>(std::clamp(i, double(-kHalf), double(kHalf - 1))) + kHalf;
    key = (key << 21) | static_cast<std::uint64_t>(c);
  }
  return key;
}
}  // namespace

Map::Map(const MapConfig& config) : config_(config), archive_voxel_(config.archive_voxel_m) { config_.validate(); }

void Map::clear() {
  orphans_.clear();
  landmarks_.clear();
  keyframes_.clear();
}

Landmark* Map::landmark(std::uint64_t id) {
  auto it = landmarks_.find(id);
  return it == landmarks_.end() ? nullptr : &it->second;
}

const Landmark* Map::landmark(std::uint64_t id) const {
  auto it = landmarks_.find(id);
  return it == landmarks_.end() ? nullptr : &it->second;
}

Landmark& Map::addLandmark(std::uint64_t id, const Eigen::Vector3d& p_w, std::uint8_t intensity) {
  Landmark& l = landmarks_[id];
  l = Landmark{};
  l.id = id;
  l.p_w = p_w;
  l.intensity = intensity;
  for (const Keyframe& kf : keyframes_) {
    auto it = kf.observations.find(id);
    if (it != kf.observations.end()) {
      l.observations.push_back({kf.frame_index, it->second});
      ++l.num_observations;
    }
  }
  return l;
}

void Map::removeLandmark(std::uint64_t id) { landmarks_.erase(id); }

Keyframe& Map::addKeyframe(Keyframe keyframe) {
  for (const auto& obs : keyframe.observations) {
    if (Landmark* l = landmark(obs.first)) {
      ++l->num_observations;
      l->observations.push_back({keyframe.frame_index, obs.second});
    }
  }
  keyframes_.push_back(std::move(keyframe));
  while (static_cast<int>(keyframes_.size()) > config_.max_keyframes) {
    Keyframe oldest = std::move(keyframes_.front());
    keyframes_.pop_front();
    retireKeyframe(oldest);
  }
  return keyframes_.back();
}

void Map::retireKeyframe(const Keyframe& retired) {
  const std::uint64_t oldest = keyframes_.empty() ? 0 : keyframes_.front().frame_index;
  // Landmarks that lost their last keyframe observation while still tracked:
  // retire them once they are no longer seen either.
  std::vector<std::uint64_t> still_orphans;
  for (std::uint64_t id : orphans_) {
    auto it = landmarks_.find(id);
    if (it == landmarks_.end() || !it->second.observations.empty()) continue;
    if (it->second.last_seen_frame < oldest) {
      archive(it->second);
      landmarks_.erase(it);
    } else {
      still_orphans.push_back(id);
    }
  }
  orphans_.swap(still_orphans);
  for (const auto& obs : retired.observations) {
    auto it = landmarks_.find(obs.first);
    if (it == landmarks_.end()) continue;
    Landmark& l = it->second;
    auto& v = l.observations;
    v.erase(std::remove_if(v.begin(), v.end(),
                           [&](const LandmarkObservation& o) { return o.keyframe == retired.frame_index; }),
            v.end());
    if (!v.empty()) continue;
    if (l.last_seen_frame < oldest) {
      archive(l);
      landmarks_.erase(it);
    } else {
      orphans_.push_back(l.id);
    }
  }
}

void Map::archive(const Landmark& l) {
  if (l.num_observations < config_.min_observations_to_archive) return;
  if (!l.p_w.allFinite()) return;
  if (archive_voxel_ > 0.0 && !archive_voxels_.insert(voxelKey(l.p_w, archive_voxel_)).second) return;
  archive_.push_back({l.p_w, l.intensity});
  if (archive_.size() >= config_.max_archive_points) coarsenArchive();
}

void Map::coarsenArchive() {
  if (archive_voxel_ <= 0.0) {
    Eigen::Vector3d lo = archive_.front().p_w, hi = lo;
    for (const ArchivedPoint& a : archive_) {
      lo = lo.cwiseMin(a.p_w);
      hi = hi.cwiseMax(a.p_w);
    }
    archive_voxel_ = std::max((hi - lo).norm() / 2048.0, 1e-9);
  }
  // Keep the first point of each voxel; double the voxel until at most half the
  // cap remain, so the next thinning is far off.
  std::vector<ArchivedPoint> kept;
  while (true) {
    archive_voxels_.clear();
    kept.clear();
    for (const ArchivedPoint& a : archive_) {
      if (archive_voxels_.insert(voxelKey(a.p_w, archive_voxel_)).second) kept.push_back(a);
    }
    if (kept.size() <= config_.max_archive_points / 2) break;
    archive_voxel_ *= 2.0;
  }
  archive_.swap(kept);
}

std::vector<ArchivedPoint> Map::allPoints() const {
  std::vector<ArchivedPoint> out;
  out.reserve(landmarks_.size() + archive_.size());
  for (const auto& kv : landmarks_) out.push_back({kv.second.p_w, kv.second.intensity});
  out.insert(out.end(), archive_.begin(), archive_.end());
  return out;
}

}  // namespace vitamin_e::map
