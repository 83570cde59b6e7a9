#include "vitamin_e/map/map.h"

#include <cmath>
#include <stdexcept>
#include <unordered_set>

namespace vitamin_e::map {

void MapConfig::validate() const {
  if (max_keyframes < 2) throw std::invalid_argument("map.max_keyframes must be >= 2");
  if (!(archive_voxel_m >= 0.0)) throw std::invalid_argument("map.archive_voxel_m must be >= 0");
  if (min_observations_to_archive < 1) throw std::invalid_argument("map.min_observations_to_archive must be >= 1");
}

Map::Map(const MapConfig& config) : config_(config) { config_.validate(); }

void Map::clear() {
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
  l.id = id;
  l.p_w = p_w;
  l.intensity = intensity;
  return l;
}

void Map::removeLandmark(std::uint64_t id) { landmarks_.erase(id); }

Keyframe& Map::addKeyframe(Keyframe keyframe) {
  for (const auto& obs : keyframe.observations) {
    if (Landmark* l = landmark(obs.first)) ++l->num_observations;
  }
  keyframes_.push_back(std::move(keyframe));
  bool retired = false;
  while (static_cast<int>(keyframes_.size()) > config_.max_keyframes) {
    keyframes_.pop_front();
    retired = true;
  }
  if (retired) retireUnobservedLandmarks();
  return keyframes_.back();
}

void Map::retireUnobservedLandmarks() {
  std::unordered_set<std::uint64_t> observed;
  for (const Keyframe& kf : keyframes_) {
    for (const auto& obs : kf.observations) observed.insert(obs.first);
  }
  const std::uint64_t oldest = keyframes_.empty() ? 0 : keyframes_.front().frame_index;
  for (auto it = landmarks_.begin(); it != landmarks_.end();) {
    const Landmark& l = it->second;
    if (!observed.count(l.id) && l.last_seen_frame < oldest) {
      archive(l);
      it = landmarks_.erase(it);
    } else {
      ++it;
    }
  }
}

void Map::archive(const Landmark& l) {
  if (l.num_observations < config_.min_observations_to_archive) return;
  if (!l.p_w.allFinite()) return;
  if (archive_.size() >= config_.max_archive_points) return;
  if (config_.archive_voxel_m > 0.0) {
    const double s = 1.0 / config_.archive_voxel_m;
    const std::int64_t ix = static_cast<std::int64_t>(std::floor(l.p_w.x() * s));
    const std::int64_t iy = static_cast<std::int64_t>(std::floor(l.p_w.y() * s));
    const std::int64_t iz = static_cast<std::int64_t>(std::floor(l.p_w.z() * s));
    const std::int64_t key = (ix * 73856093) ^ (iy * 19349663) ^ (iz * 83492791);
    if (archive_voxels_.count(key)) return;
    archive_voxels_[key] = archive_.size();
  }
  archive_.push_back({l.p_w, l.intensity});
}

std::vector<ArchivedPoint> Map::allPoints() const {
  std::vector<ArchivedPoint> out;
  out.reserve(landmarks_.size() + archive_.size());
  for (const auto& kv : landmarks_) out.push_back({kv.second.p_w, kv.second.intensity});
  out.insert(out.end(), archive_.begin(), archive_.end());
  return out;
}

}  // namespace vitamin_e::map
