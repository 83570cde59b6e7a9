#include "vitamin_e/pipeline/relocalizer.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>

#include "vitamin_e/common/rounding.h"

namespace vitamin_e::pipeline {

void RelocalizerConfig::validate() const {
  auto check = [](bool ok, const char* what) {
    if (!ok) throw std::invalid_argument(std::string("relocalization.") + what);
  };
  check(max_frames >= 1, "max_frames must be >= 1");
  check(max_keyframes >= 1, "max_keyframes must be >= 1");
  check(points_per_keyframe >= 10, "points_per_keyframe must be >= 10");
  check(max_shared_points >= 0.0 && max_shared_points <= 1.0, "max_shared_points must be in [0, 1]");
  check(query_points >= 10, "query_points must be >= 10");
  check(candidates >= 1, "candidates must be >= 1");
  check(patch_size >= 7 && patch_size % 2 == 1, "patch_size must be odd and >= 7");
  check(smoothing_sigma > 0.0, "smoothing_sigma must be > 0");
  check(max_distance >= 0 && max_distance <= 256, "max_distance must be in [0, 256]");
  check(ratio > 0.0 && ratio <= 1.0, "ratio must be in (0, 1]");
  check(min_inliers >= 6, "min_inliers must be >= 6");
  check(min_inlier_ratio > 0.0 && min_inlier_ratio <= 1.0, "min_inlier_ratio must be in (0, 1]");
}

Relocalizer::Relocalizer(const RelocalizerConfig& config, const camera::Camera& camera, const geometry::PnpConfig& pnp)
    : config_(config), camera_(camera), pnp_(pnp), brief_(config.patch_size), brief_upside_down_(brief_.rotated(2)) {
  config_.validate();
  // Disjoint bit sets for the tables, from a fixed shuffle of the 256 tests.
  std::array<int, 256> order;
  for (int i = 0; i < 256; ++i) order[i] = i;
  std::uint64_t state = 0x9e3779b97f4a7c15ull;
  for (int i = 255; i > 0; --i) {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    std::swap(order[i], order[static_cast<int>((state >> 33) % static_cast<std::uint64_t>(i + 1))]);
  }
  key_bits_.resize(kTables);
  for (int t = 0; t < kTables; ++t) {
    for (int b = 0; b < kKeyBits - 1; ++b) key_bits_[t][b] = order[t * (kKeyBits - 1) + b];
  }
  buckets_.assign(kTables, std::vector<std::vector<std::uint32_t>>(std::size_t{1} << kKeyBits));
}

std::uint32_t Relocalizer::key(int table, const tracking::BriefDescriptor& d, signed char polarity) const {
  std::uint32_t k = polarity > 0 ? 1u : 0u;
  for (int b : key_bits_[table]) k = (k << 1) | static_cast<std::uint32_t>((d.bits[b >> 6] >> (b & 63)) & 1u);
  return k;
}

void Relocalizer::hashEntry(const Entry& e, bool insert) {
  for (int t = 0; t < kTables; ++t) {
    for (std::size_t i = 0; i < e.points.size(); ++i) {
      std::vector<std::uint32_t>& bucket = buckets_[t][key(t, e.descriptors[i], e.polarities[i])];
      if (insert) {
        if (bucket.empty() || bucket.back() != e.serial) bucket.push_back(e.serial);
      } else {
        bucket.erase(std::remove(bucket.begin(), bucket.end(), e.serial), bucket.end());
      }
    }
  }
}

void Relocalizer::clear() {
  entries_.clear();
  for (auto& table : buckets_) {
    for (auto& bucket : table) bucket.clear();
  }
}

std::vector<map::IndexedKeyframe> Relocalizer::exportEntries() const {
  std::vector<map::IndexedKeyframe> out;
  out.reserve(entries_.size());
  for (const Entry& e : entries_) {
    map::IndexedKeyframe k;
    k.frame_index = e.frame_index;
    k.T_w_c = e.T_w_c;
    k.points.reserve(e.points.size());
    for (const Point& p : e.points) {
      map::IndexedPoint q;
      q.landmark_id = p.landmark_id;
      q.p_w = p.p_w;
      q.descriptor = p.descriptor.bits;
      q.polarity = p.polarity;
      k.points.push_back(q);
    }
    out.push_back(std::move(k));
  }
  return out;
}

void Relocalizer::importEntries(const std::vector<map::IndexedKeyframe>& entries) {
  clear();
  const std::size_t keep = std::min(entries.size(), static_cast<std::size_t>(config_.max_keyframes));
  for (std::size_t i = entries.size() - keep; i < entries.size(); ++i) {
    const map::IndexedKeyframe& k = entries[i];
    Entry e;
    e.serial = next_serial_++;
    e.frame_index = k.frame_index;
    e.T_w_c = k.T_w_c;
    e.points.reserve(k.points.size());
    e.descriptors.reserve(k.points.size());
    e.polarities.reserve(k.points.size());
    for (const map::IndexedPoint& q : k.points) {
      Point p;
      p.landmark_id = q.landmark_id;
      p.p_w = q.p_w;
      p.descriptor.bits = q.descriptor;
      p.polarity = q.polarity;
      e.descriptors.push_back(p.descriptor);
      e.polarities.push_back(p.polarity);
      e.points.push_back(p);
    }
    entries_.push_back(std::move(e));
  }
  // The hash tables in one pass per table: bucket sizes counted first, so that
  // a large index is not built by hundreds of thousands of reallocations.
  std::vector<std::uint32_t> keys;
  std::vector<std::uint32_t> count(std::size_t{1} << kKeyBits);
  for (int t = 0; t < kTables; ++t) {
    keys.clear();
    std::fill(count.begin(), count.end(), 0u);
    for (const Entry& e : entries_) {
      for (std::size_t i = 0; i < e.points.size(); ++i) {
        keys.push_back(key(t, e.descriptors[i], e.polarities[i]));
        ++count[keys.back()];
      }
    }
    for (std::size_t b = 0; b < count.size(); ++b) buckets_[t][b].reserve(count[b]);
    std::size_t next = 0;
    for (const Entry& e : entries_) {
      for (std::size_t i = 0; i < e.points.size(); ++i) {
        std::vector<std::uint32_t>& bucket = buckets_[t][keys[next++]];
        if (bucket.empty() || bucket.back() != e.serial) bucket.push_back(e.serial);
      }
    }
  }
}

cv::Mat Relocalizer::smooth(const cv::Mat& image) const {
  cv::Mat s;
  cv::GaussianBlur(image, s, cv::Size(0, 0), config_.smoothing_sigma);
  return s;
}

std::vector<std::size_t> Relocalizer::spread(const FrameContext& frame, const std::vector<bool>& use,
                                             int max_count) const {
  std::vector<std::size_t> idx;
  for (std::size_t i = 0; i < frame.tracks.size(); ++i) {
    if (use[i]) idx.push_back(i);
  }
  if (static_cast<int>(idx.size()) <= max_count) return idx;
  // Round robin over grid cells, so that every part of the image keeps points.
  const int cells_x = 16, cells_y = std::max(4, 16 * camera_.height() / std::max(1, camera_.width()));
  std::vector<std::vector<std::size_t>> cells(static_cast<std::size_t>(cells_x * cells_y));
  for (std::size_t i : idx) {
    const Eigen::Vector2f& uv = frame.tracks[i].uv;
    const int cx = std::clamp(
        static_cast<int>(uv.x() * static_cast<float>(cells_x) / static_cast<float>(camera_.width())), 0, cells_x - 1);
    const int cy = std::clamp(
        static_cast<int>(uv.y() * static_cast<float>(cells_y) / static_cast<float>(camera_.height())), 0, cells_y - 1);
    const int cell = cy * cells_x + cx;
    cells[static_cast<std::size_t>(cell)].push_back(i);
  }
  std::vector<std::size_t> out;
  out.reserve(static_cast<std::size_t>(max_count));
  for (std::size_t round = 0; static_cast<int>(out.size()) < max_count; ++round) {
    bool any = false;
    for (const auto& c : cells) {
      if (round < c.size()) {
        any = true;
        out.push_back(c[round]);
        if (static_cast<int>(out.size()) >= max_count) break;
      }
    }
    if (!any) break;
  }
  return out;
}

void Relocalizer::rescale(const Eigen::Vector3d& centre_w, double factor) {
  for (Entry& e : entries_) {
    e.T_w_c.translation() = centre_w + factor * (e.T_w_c.translation() - centre_w);
    for (Point& p : e.points) p.p_w = centre_w + factor * (p.p_w - centre_w);
  }
}

bool Relocalizer::addKeyframe(const cv::Mat& image, const FrameContext& frame, const map::Map& map,
                              const Eigen::Isometry3d& T_w_c) {
  if (!config_.enabled || image.empty()) return false;
  Entry e;
  e.frame_index = frame.frame_index;
  e.T_w_c = T_w_c;
  std::vector<const map::Landmark*> landmarks(frame.tracks.size());
  std::vector<bool> mapped(frame.tracks.size());
  for (std::size_t i = 0; i < frame.tracks.size(); ++i) {
    landmarks[i] = map.landmark(frame.tracks[i].id);
    mapped[i] = landmarks[i] != nullptr;
  }
  if (config_.max_shared_points < 1.0 && sharedWithNewest(landmarks) > config_.max_shared_points) return false;
  const cv::Mat smoothed = smooth(image);
  for (std::size_t i : spread(frame, mapped, config_.points_per_keyframe)) {
    const FrameTrack& t = frame.tracks[i];
    Point p;
    if (!brief_.describe(smoothed, common::roundHalfAway(t.uv.x()), common::roundHalfAway(t.uv.y()), &p.descriptor)) {
      continue;
    }
    p.landmark_id = landmarks[i]->id;
    p.p_w = landmarks[i]->p_w;
    p.polarity = t.polarity;
    e.descriptors.push_back(p.descriptor);
    e.polarities.push_back(p.polarity);
    e.points.push_back(p);
  }
  if (e.points.size() < static_cast<std::size_t>(config_.min_inliers)) return false;
  // Serials only for entries kept: relocalize() finds an entry at serial - first serial.
  e.serial = next_serial_++;
  hashEntry(e, true);
  entries_.push_back(std::move(e));
  while (static_cast<int>(entries_.size()) > config_.max_keyframes) {
    hashEntry(entries_.front(), false);
    entries_.pop_front();
  }
  return true;
}

double Relocalizer::sharedWithNewest(const std::vector<const map::Landmark*>& landmarks) const {
  if (entries_.empty() || entries_.back().points.empty()) return 0.0;
  std::vector<std::uint64_t> seen;
  seen.reserve(landmarks.size());
  for (const map::Landmark* l : landmarks) {
    if (l != nullptr) seen.push_back(l->id);
  }
  std::sort(seen.begin(), seen.end());
  std::size_t shared = 0;
  for (const Point& p : entries_.back().points) {
    if (std::binary_search(seen.begin(), seen.end(), p.landmark_id)) ++shared;
  }
  return static_cast<double>(shared) / static_cast<double>(entries_.back().points.size());
}

Relocalization Relocalizer::relocalize(const cv::Mat& image, const FrameContext& frame, const map::Map& map) const {
  Relocalization best;
  best.why = "no keyframe to relocalize against";
  if (!config_.enabled || entries_.empty() || image.empty()) return best;
  if (static_cast<int>(frame.tracks.size()) < config_.min_inliers) {
    best.why = "too few tracks (" + std::to_string(frame.tracks.size()) + ")";
    return best;
  }
  // The frame's tracks, described once per orientation tried.
  const cv::Mat smoothed = smooth(image);
  const std::vector<bool> all(frame.tracks.size(), true);
  const std::vector<std::size_t> query = spread(frame, all, config_.query_points);
  struct Described {
    std::vector<tracking::BriefDescriptor> descriptors;
    std::vector<signed char> polarities;
    std::vector<std::size_t> track;  // index into frame.tracks
  };
  const int orientations = config_.upside_down ? 2 : 1;
  Described described[2];
  for (int o = 0; o < orientations; ++o) {
    const tracking::BriefExtractor& b = o == 0 ? brief_ : brief_upside_down_;
    Described& d = described[o];
    for (std::size_t i : query) {
      const FrameTrack& t = frame.tracks[i];
      tracking::BriefDescriptor desc;
      if (!b.describe(smoothed, common::roundHalfAway(t.uv.x()), common::roundHalfAway(t.uv.y()), &desc)) {
        continue;
      }
      d.descriptors.push_back(desc);
      d.polarities.push_back(t.polarity);
      d.track.push_back(i);
    }
  }
  // Candidates: the newest keyframe (a short loss resumes where tracking
  // stopped), then the keyframes the frame's tracks collide with most in the
  // hash tables, per orientation. A collision weighs 1 / (keyframes in its
  // bucket): a key many keyframes share says little; a track votes once per keyframe.
  struct Candidate {
    double votes;
    std::size_t entry;
    int orientation;  // 0 upright, 1 upside down
  };
  const std::uint32_t first_serial = entries_.front().serial;
  std::vector<Candidate> candidates;
  std::vector<double> votes(entries_.size()), best_weight(entries_.size());
  std::vector<int> last_voter(entries_.size());
  for (int o = 0; o < orientations; ++o) {
    std::fill(votes.begin(), votes.end(), 0.0);
    std::fill(last_voter.begin(), last_voter.end(), -1);
    const Described& d = described[o];
    for (std::size_t q = 0; q < d.descriptors.size(); ++q) {
      for (int t = 0; t < kTables; ++t) {
        const std::vector<std::uint32_t>& bucket = buckets_[t][key(t, d.descriptors[q], d.polarities[q])];
        const double w = bucket.empty() ? 0.0 : 1.0 / static_cast<double>(bucket.size());
        for (std::uint32_t serial : bucket) {
          const std::size_t k = serial - first_serial;  // entries_ are in serial order
          if (k >= entries_.size()) continue;
          if (last_voter[k] != static_cast<int>(q)) {
            last_voter[k] = static_cast<int>(q);
            best_weight[k] = 0.0;
          }
          if (w > best_weight[k]) {
            votes[k] += w - best_weight[k];
            best_weight[k] = w;
          }
        }
      }
    }
    for (std::size_t k = 0; k < entries_.size(); ++k) {
      if (votes[k] > 0.0) candidates.push_back({votes[k], k, o});
    }
  }
  const std::size_t n = std::min<std::size_t>(candidates.size(), static_cast<std::size_t>(config_.candidates));
  std::partial_sort(candidates.begin(), candidates.begin() + static_cast<std::ptrdiff_t>(n), candidates.end(),
                    [](const Candidate& a, const Candidate& b) {
                      return a.votes > b.votes || (a.votes == b.votes && a.entry > b.entry);
                    });
  candidates.resize(n);
  const std::size_t newest = entries_.size() - 1;
  if (std::none_of(candidates.begin(), candidates.end(),
                   [&](const Candidate& c) { return c.entry == newest && c.orientation == 0; })) {
    candidates.insert(candidates.begin(), Candidate{0.0, newest, 0});
  }

  tracking::MatchConfig match;
  match.max_distance = config_.max_distance;
  match.ratio = config_.ratio;
  match.cross_check = true;
  // Each candidate's matches and pose, independent of the others: on OpenCV's
  // worker threads (a lost frame's matching is most of its cost); chosen below in
  // the candidates' order, so the answer does not depend on the threads.
  struct Tried {
    int matches = 0;
    geometry::PnpResult pose;
  };
  std::vector<Tried> tried(candidates.size());
  cv::parallel_for_(cv::Range(0, static_cast<int>(candidates.size())), [&](const cv::Range& range) {
    for (int n = range.start; n < range.end; ++n) {
      const Candidate& c = candidates[static_cast<std::size_t>(n)];
      const Entry& e = entries_[c.entry];
      const Described& d = described[c.orientation];
      const auto pairs = tracking::matchBrief(d.descriptors, e.descriptors, match, &d.polarities, &e.polarities);
      Tried& t = tried[static_cast<std::size_t>(n)];
      t.matches = static_cast<int>(pairs.size());
      if (t.matches < config_.min_inliers) continue;
      std::vector<Eigen::Vector3d> p_w;
      std::vector<Eigen::Vector2d> xy;
      p_w.reserve(pairs.size());
      xy.reserve(pairs.size());
      for (const auto& [q, k] : pairs) {
        const Point& p = e.points[static_cast<std::size_t>(k)];
        const map::Landmark* l = map.landmark(p.landmark_id);
        p_w.push_back(l ? l->p_w : p.p_w);
        xy.push_back(frame.tracks[d.track[static_cast<std::size_t>(q)]].xy);
      }
      t.pose = geometry::solvePnpRansac(p_w, xy, pnp_, nullptr);
    }
  });
  best.why = "no keyframe gave a pose";
  for (std::size_t n = 0; n < candidates.size(); ++n) {
    const Candidate& c = candidates[n];
    const Entry& e = entries_[c.entry];
    const Tried& t = tried[n];
    if (t.matches < config_.min_inliers) {
      if (best.matches == 0) best.why = "too few descriptor matches (" + std::to_string(t.matches) + ")";
      continue;
    }
    const geometry::PnpResult& r = t.pose;
    const double ratio = static_cast<double>(r.num_inliers) / static_cast<double>(t.matches);
    if (!r.ok || r.num_inliers < config_.min_inliers || ratio < config_.min_inlier_ratio) {
      if (t.matches > best.matches) {
        best.matches = t.matches;
        best.inliers = r.num_inliers;
        best.why = "P3P found " + std::to_string(r.num_inliers) + " inliers of " + std::to_string(t.matches) +
                   " matches with keyframe " + std::to_string(e.frame_index);
      }
      continue;
    }
    if (best.ok && r.num_inliers <= best.inliers) continue;
    best.ok = true;
    best.why.clear();
    best.T_w_c = r.T_w_c;
    best.keyframe = e.frame_index;
    best.quarter_turns = 2 * c.orientation;
    best.matches = t.matches;
    best.inliers = r.num_inliers;
    best.votes = c.votes;
  }
  return best;
}

}  // namespace vitamin_e::pipeline
