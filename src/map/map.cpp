#include "vitamin_e/map/map.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace vitamin_e::map {

void MapConfig::validate() const {
  if (max_keyframes < 2) throw std::invalid_argument("map.max_keyframes must be >= 2");
  if (keep_newest_keyframes < 1) throw std::invalid_argument("map.keep_newest_keyframes must be >= 1");
  if (!(anchor_loss_share >= 0.0 && anchor_loss_share <= 1.0)) {
    throw std::invalid_argument("map.anchor_loss_share must be in [0, 1]");
  }
  if (retire_oldest_beyond_frames < 0) throw std::invalid_argument("map.retire_oldest_beyond_frames must be >= 0");
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
  dormant_dropped_ += dormant_.size();
  dormant_.clear();  // a new map has a new scale and frame: the old points do not fit it
  landmarks_.clear();
  keyframes_.clear();
}

Landmark* Map::find(std::uint64_t id) {
  auto it = landmarks_.find(id);
  return it == landmarks_.end() ? nullptr : &it->second;
}

const Landmark* Map::landmark(std::uint64_t id) const {
  auto it = landmarks_.find(id);
  return it == landmarks_.end() ? nullptr : &it->second;
}

const Landmark& Map::addLandmark(const NewLandmark& n) {
  Landmark& l = landmarks_[n.id];
  l = Landmark{};
  l.id = n.id;
  l.p_w = n.p_w;
  l.intensity = n.intensity;
  l.polarity = n.polarity;
  l.last_seen_frame = n.seen_frame;
  l.num_observations = n.prior_observations;
  for (const Keyframe& kf : keyframes_) {
    auto it = kf.observations.find(n.id);
    if (it != kf.observations.end()) {
      l.observations.push_back({kf.frame_index, it->second});
      ++l.num_observations;
    }
  }
  return l;
}

void Map::removeLandmark(std::uint64_t id) { landmarks_.erase(id); }

void Map::detachLandmark(std::uint64_t id) {
  auto it = landmarks_.find(id);
  if (it == landmarks_.end()) return;
  retireLandmark(it->second);
  landmarks_.erase(it);
}

void Map::setLandmarkPosition(std::uint64_t id, const Eigen::Vector3d& p_w) {
  if (Landmark* l = find(id)) l->p_w = p_w;
}

void Map::markSeen(std::uint64_t id, std::uint64_t frame_index) {
  if (Landmark* l = find(id)) l->last_seen_frame = frame_index;
}

void Map::markAllSeen(std::uint64_t frame_index) {
  for (auto& kv : landmarks_) kv.second.last_seen_frame = frame_index;
}

int Map::flagOutlier(std::uint64_t id) {
  Landmark* l = find(id);
  return l ? ++l->outlier_count : 0;
}

void Map::setKeyframePose(std::size_t index, const Eigen::Isometry3d& T_w_c) {
  if (index < keyframes_.size()) keyframes_[index].T_w_c = T_w_c;
}

void Map::rescale(const Eigen::Vector3d& centre_w, double factor) {
  auto scaled = [&](const Eigen::Vector3d& x) -> Eigen::Vector3d { return centre_w + factor * (x - centre_w); };
  for (Keyframe& k : keyframes_) k.T_w_c.translation() = scaled(k.T_w_c.translation());
  for (auto& kv : landmarks_) kv.second.p_w = scaled(kv.second.p_w);
  for (DormantLandmark& d : dormant_) d.p_w = scaled(d.p_w);
}

const Keyframe& Map::addKeyframe(Keyframe keyframe) {
  for (const auto& obs : keyframe.observations) {
    if (Landmark* l = find(obs.first)) {
      ++l->num_observations;
      l->observations.push_back({keyframe.frame_index, obs.second});
    }
  }
  keyframes_.push_back(std::move(keyframe));
  while (static_cast<int>(keyframes_.size()) > config_.max_keyframes) {
    const std::size_t k = keyframeToRetire();
    Keyframe retired = std::move(keyframes_[k]);
    keyframes_.erase(keyframes_.begin() + static_cast<long>(k));
    retireKeyframe(retired, keyframes_[k].frame_index);
  }
  return keyframes_.back();
}

namespace {
// The widest angle [rad] between two of the rays, leaving ray `skip` out (-1: none); 0 with fewer than two.
double widestAngle(const std::vector<Eigen::Vector3d>& rays, int skip, int* first = nullptr, int* second = nullptr) {
  double min_dot = 2.0;
  const int n = static_cast<int>(rays.size());
  for (int i = 0; i < n; ++i) {
    if (i == skip) continue;
    for (int j = i + 1; j < n; ++j) {
      if (j == skip) continue;
      const double d = rays[i].dot(rays[j]);
      if (d < min_dot) {
        min_dot = d;
        if (first) *first = i;
        if (second) *second = j;
      }
    }
  }
  return min_dot > 1.5 ? 0.0 : std::acos(std::clamp(min_dot, -1.0, 1.0));
}
}  // namespace

std::size_t Map::keyframeToRetire() const {
  const int n = static_cast<int>(keyframes_.size());
  const int candidates = n - config_.keep_newest_keyframes;
  if (!config_.retire_least_parallax || candidates <= 1) return 0;
  if (config_.retire_oldest_beyond_frames > 0 && keyframes_.back().frame_index - keyframes_.front().frame_index >
                                                     static_cast<std::uint64_t>(config_.retire_oldest_beyond_frames)) {
    return 0;
  }
  std::unordered_map<std::uint64_t, int> index_of;
  for (int k = 0; k < n; ++k) index_of.emplace(keyframes_[static_cast<std::size_t>(k)].frame_index, k);
  // Per keyframe, the parallax the points of the newest keyframe would lose without it:
  // for each point, its widest angle between two observing keyframes' rays, with and
  // without the keyframe (only the two keyframes of the widest pair can lose any); or,
  // retire_fewest_reliant, how many points would keep less than half their widest angle.
  std::vector<double> loss(static_cast<std::size_t>(n), 0.0), anchored(static_cast<std::size_t>(n), 0.0);
  std::vector<Eigen::Vector3d> rays;
  std::vector<int> observer;
  for (const auto& obs : keyframes_.back().observations) {
    const Landmark* l = landmark(obs.first);
    if (!l || l->observations.size() < 2) continue;
    rays.clear();
    observer.clear();
    for (const LandmarkObservation& o : l->observations) {
      auto it = index_of.find(o.keyframe);
      if (it == index_of.end()) continue;
      const Keyframe& kf = keyframes_[static_cast<std::size_t>(it->second)];
      rays.push_back((kf.T_w_c.rotation() * o.xy.homogeneous()).normalized());
      observer.push_back(it->second);
    }
    int a = -1, b = -1;
    const double widest = widestAngle(rays, -1, &a, &b);
    if (a < 0) continue;
    for (int e : {a, b}) {
      const double without = widestAngle(rays, e);
      anchored[static_cast<std::size_t>(observer[e])] += widest;
      loss[static_cast<std::size_t>(observer[e])] +=
          config_.retire_fewest_reliant ? (without < 0.5 * widest ? 1.0 : 0.0) : widest - without;
    }
  }
  if (config_.retire_oldest_unless_anchor && !(loss[0] > config_.anchor_loss_share * anchored[0])) return 0;
  // The cheapest; among equals (none of them sees the current points) the oldest.
  int best = 0;
  for (int k = 1; k < candidates; ++k) {
    if (loss[static_cast<std::size_t>(k)] < loss[static_cast<std::size_t>(best)]) best = k;
  }
  return static_cast<std::size_t>(best);
}

void Map::retireKeyframe(const Keyframe& retired, std::uint64_t next_keyframe) {
  // Landmarks that lost their last keyframe observation while still tracked:
  // retire them once they are no longer seen either (not since the keyframe
  // after the retired one).
  const std::uint64_t oldest = next_keyframe;
  std::vector<std::uint64_t> still_orphans;
  for (std::uint64_t id : orphans_) {
    auto it = landmarks_.find(id);
    if (it == landmarks_.end() || !it->second.observations.empty()) continue;
    if (it->second.last_seen_frame < oldest) {
      retireLandmark(it->second);
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
      retireLandmark(l);
      landmarks_.erase(it);
    } else {
      orphans_.push_back(l.id);
    }
  }
}

void Map::retireLandmark(const Landmark& l) {
  // A revived landmark was archived when it first retired: no second copy.
  if (!l.revived) archive(l);
  if (config_.max_dormant_landmarks == 0 || l.num_observations < config_.min_observations_to_archive ||
      !l.p_w.allFinite()) {
    return;
  }
  DormantLandmark d;
  d.id = l.id;
  d.p_w = l.p_w;
  d.intensity = l.intensity;
  d.polarity = l.polarity;
  d.num_observations = l.num_observations;
  dormant_.push_back(d);
  while (dormant_.size() > config_.max_dormant_landmarks) {
    dormant_.pop_front();
    ++dormant_dropped_;
  }
}

namespace {
bool observedByBoth(const std::deque<Keyframe>& keyframes, std::uint64_t a, std::uint64_t b) {
  for (const Keyframe& kf : keyframes) {
    if (kf.observations.count(a) && kf.observations.count(b)) return true;
  }
  return false;
}
}  // namespace

bool Map::relabelLandmark(std::uint64_t old_id, std::uint64_t new_id, std::uint64_t frame_index,
                          std::int8_t track_polarity) {
  auto it = landmarks_.find(old_id);
  if (it == landmarks_.end() || old_id == new_id || landmarks_.count(new_id)) return false;
  if (observedByBoth(keyframes_, old_id, new_id)) return false;
  Landmark l = std::move(it->second);
  landmarks_.erase(it);
  l.id = new_id;
  for (Keyframe& kf : keyframes_) {
    const auto old_obs = kf.observations.find(old_id);
    if (old_obs != kf.observations.end()) {
      kf.observations.emplace(new_id, old_obs->second);
      kf.observations.erase(old_obs);
      continue;
    }
    const auto new_obs = kf.observations.find(new_id);
    if (new_obs != kf.observations.end()) {
      l.observations.push_back({kf.frame_index, new_obs->second});
      ++l.num_observations;
    }
  }
  std::sort(l.observations.begin(), l.observations.end(),
            [](const LandmarkObservation& a, const LandmarkObservation& b) { return a.keyframe < b.keyframe; });
  for (std::uint64_t& id : orphans_) {
    if (id == old_id) id = new_id;
  }
  if (l.observations.empty() && std::find(orphans_.begin(), orphans_.end(), new_id) == orphans_.end()) {
    orphans_.push_back(new_id);
  }
  l.last_seen_frame = frame_index;
  if (l.polarity == 0) l.polarity = track_polarity;
  landmarks_.emplace(new_id, std::move(l));
  return true;
}

bool Map::reviveDormant(std::size_t index, std::uint64_t track_id, std::uint64_t frame_index,
                        std::int8_t track_polarity) {
  if (index >= dormant_.size() || dormant_[index].revived || landmarks_.count(track_id)) return false;
  DormantLandmark& d = dormant_[index];
  NewLandmark n;
  n.id = track_id;
  n.p_w = d.p_w;
  n.intensity = d.intensity;
  n.polarity = d.polarity != 0 ? d.polarity : track_polarity;
  n.seen_frame = frame_index;
  n.prior_observations = d.num_observations;
  addLandmark(n);
  Landmark* l = find(track_id);
  l->revived = true;
  if (l->observations.empty()) orphans_.push_back(track_id);
  d.revived = true;
  return true;
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

MapSnapshot Map::snapshot() const {
  MapSnapshot s;
  s.keyframes.assign(keyframes_.begin(), keyframes_.end());
  s.landmarks.reserve(landmarks_.size());
  for (const auto& kv : landmarks_) {
    s.landmarks.push_back(kv.second);
    s.landmarks.back().observations.clear();
  }
  std::sort(s.landmarks.begin(), s.landmarks.end(), [](const Landmark& a, const Landmark& b) { return a.id < b.id; });
  s.dormant.assign(dormant_.begin(), dormant_.end());
  s.dormant_dropped = dormant_dropped_;
  s.archive = archive_;
  s.archive_voxel = archive_voxel_;
  return s;
}

namespace {
void check(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument("map snapshot: " + what);
}
bool finitePose(const Eigen::Isometry3d& T) {
  if (!T.matrix().allFinite()) return false;
  const Eigen::Matrix3d R = T.linear();
  return (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() < 1e-6 && R.determinant() > 0.0;
}
}  // namespace

void Map::restore(const MapSnapshot& s) {
  // Checked completely before anything changes.
  for (std::size_t k = 0; k < s.keyframes.size(); ++k) {
    const Keyframe& kf = s.keyframes[k];
    const std::string name = "keyframe " + std::to_string(kf.frame_index);
    check(k == 0 || kf.frame_index > s.keyframes[k - 1].frame_index, name + " is not newer than the one before it");
    check(std::isfinite(kf.timestamp), name + " has a non-finite timestamp");
    check(finitePose(kf.T_w_c), name + " has no valid pose");
    for (const auto& o : kf.observations) check(o.second.allFinite(), name + " has a non-finite observation");
  }
  std::unordered_map<std::uint64_t, Landmark> landmarks;
  landmarks.reserve(s.landmarks.size());
  for (const Landmark& l : s.landmarks) {
    const std::string name = "landmark " + std::to_string(l.id);
    check(l.p_w.allFinite(), name + " has a non-finite position");
    check(l.polarity >= -1 && l.polarity <= 1, name + " has a curvature sign of " + std::to_string(l.polarity));
    check(l.num_observations >= 0 && l.outlier_count >= 0, name + " has negative counts");
    Landmark copy = l;
    copy.observations.clear();
    check(landmarks.emplace(l.id, std::move(copy)).second, name + " appears twice");
  }
  for (const DormantLandmark& d : s.dormant) {
    check(d.p_w.allFinite(), "dormant landmark " + std::to_string(d.id) + " has a non-finite position");
    check(d.polarity >= -1 && d.polarity <= 1,
          "dormant landmark " + std::to_string(d.id) + " has a bad curvature sign");
  }
  for (const ArchivedPoint& a : s.archive) check(a.p_w.allFinite(), "an archived point is not finite");
  check(std::isfinite(s.archive_voxel) && s.archive_voxel >= 0.0, "the archive voxel is not a size");

  // Observations on both sides: a landmark's are the keyframes' of its track.
  for (const Keyframe& kf : s.keyframes) {
    for (const auto& o : kf.observations) {
      auto it = landmarks.find(o.first);
      if (it != landmarks.end()) it->second.observations.push_back({kf.frame_index, o.second});
    }
  }
  std::vector<std::uint64_t> orphans;
  for (const auto& kv : landmarks) {
    if (kv.second.observations.empty()) orphans.push_back(kv.first);
  }
  std::sort(orphans.begin(), orphans.end());
  landmarks_.swap(landmarks);
  keyframes_.assign(s.keyframes.begin(), s.keyframes.end());
  orphans_.swap(orphans);
  dormant_.assign(s.dormant.begin(), s.dormant.end());
  dormant_dropped_ = s.dormant_dropped;
  archive_ = s.archive;
  archive_voxel_ = std::max(s.archive_voxel, config_.archive_voxel_m);
  archive_voxels_.clear();
  if (archive_voxel_ > 0.0) {
    for (const ArchivedPoint& a : archive_) archive_voxels_.insert(voxelKey(a.p_w, archive_voxel_));
  }
  // This map's bounds apply.
  if (!archive_.empty() && archive_.size() >= config_.max_archive_points) coarsenArchive();
  while (dormant_.size() > config_.max_dormant_landmarks) {
    dormant_.pop_front();
    ++dormant_dropped_;
  }
  while (static_cast<int>(keyframes_.size()) > config_.max_keyframes) {
    Keyframe oldest = std::move(keyframes_.front());
    keyframes_.pop_front();
    retireKeyframe(oldest, keyframes_.front().frame_index);
  }
}

std::vector<ArchivedPoint> Map::allPoints() const {
  std::vector<ArchivedPoint> out;
  out.reserve(landmarks_.size() + archive_.size());
  for (const auto& kv : landmarks_) out.push_back({kv.second.p_w, kv.second.intensity});
  out.insert(out.end(), archive_.begin(), archive_.end());
  return out;
}

}  // namespace vitamin_e::map
