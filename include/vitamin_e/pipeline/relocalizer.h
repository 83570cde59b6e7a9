#pragma once
// Relocalization: finds the camera in the existing map after tracking was lost,
// so that the trajectory goes on in the same world frame and at the same scale
// instead of in a new map. Keyframes are indexed by BRIEF descriptors of their
// mapped points at full resolution (a keyframe that still sees most of the newest
// indexed one's points is left out), hashed into a few tables of descriptor bits
// (locality-sensitive hashing: a true match shares all bits of a key often
// enough). A lost frame's tracks vote for the keyframes they collide with, in
// the frame's own orientation and turned upside down; the newest and the
// best-voted keyframes' descriptors are matched to the frame's tracks (same curvature sign), and
// P3P + RANSAC gives the pose. This is the stage loop closure and map loading
// build on.
#include <array>
#include <cstdint>
#include <deque>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "vitamin_e/camera/camera.h"
#include "vitamin_e/geometry/pnp.h"
#include "vitamin_e/map/map.h"
#include "vitamin_e/map/map_file.h"
#include "vitamin_e/pipeline/frame_context.h"
#include "vitamin_e/tracking/brief.h"

namespace vitamin_e::pipeline {

struct RelocalizerConfig {
  bool enabled = true;      // false: a loss re-initializes at once (a new map)
  int max_frames = 30;      // frames with features, lost and not relocalized, before re-initializing (>= 1)
  int max_keyframes = 400;  // keyframes indexed; the oldest are dropped (>= 1)
  // A keyframe is not indexed when it still sees more than this share of the newest indexed
  // keyframe's points (a near copy: the CPU of describing it, and a place of the index taken
  // from an older part of the map), [0, 1]; 1: every keyframe.
  double max_shared_points = 0.7;
  int points_per_keyframe = 1500;  // described map points kept per keyframe, spread over the image (>= 10)
  int query_points = 2500;         // tracks of a lost frame described, spread over the image (>= 10)
  int candidates = 4;   // best-voted keyframes (and orientations) tried per lost frame, besides the newest (>= 1)
  int patch_size = 31;  // BRIEF window at full resolution [px], odd >= 7
  double smoothing_sigma = 2.0;    // Gaussian smoothing before the BRIEF tests [px] (> 0)
  int max_distance = 64;           // accepted Hamming distance (of 256)
  double ratio = 0.85;             // best / second best distance, (0, 1]
  int min_inliers = 30;            // P3P inliers to accept a pose (>= 6)
  double min_inlier_ratio = 0.25;  // of the descriptor matches, (0, 1]
  bool upside_down = true;         // also look for the frame turned by 180 degrees (a rolled camera)
  void validate() const;           // throws std::invalid_argument naming the key
};

struct Relocalization {
  bool ok = false;
  std::string why;  // when not ok
  Eigen::Isometry3d T_w_c = Eigen::Isometry3d::Identity();
  std::uint64_t keyframe = 0;  // frame index of the keyframe it was found against
  int quarter_turns = 0;       // 2: the camera is upside down relative to that keyframe
  int matches = 0;             // descriptor matches with it
  int inliers = 0;             // P3P inliers among them
  double votes = 0;            // weighted hash collisions of the frame's tracks with it (0: tried as the newest)
};

class Relocalizer {
 public:
  Relocalizer(const RelocalizerConfig& config, const camera::Camera& camera, const geometry::PnpConfig& pnp);

  // Indexes the frame as a keyframe at T_w_c: its tracks that carry a map point,
  // with their descriptors and the points' current positions. Returns false when it was not
  // indexed (disabled, no image, too few points, or a near copy of the newest entry).
  bool addKeyframe(const cv::Mat& image, const FrameContext& frame, const map::Map& map,
                   const Eigen::Isometry3d& T_w_c);
  // Looks for the frame in the index. Positions come from the map where the
  // point is still a landmark, else from the index.
  Relocalization relocalize(const cv::Mat& image, const FrameContext& frame, const map::Map& map) const;
  void clear();
  // The map was rescaled (map::Map::rescale): the indexed poses and points follow.
  void rescale(const Eigen::Vector3d& centre_w, double factor);
  // The index as plain data (oldest keyframe first), e.g. for the map file, and
  // back: importEntries replaces the index (the newest max_keyframes are kept).
  // Descriptors are only comparable between equal descriptorSettings().
  std::vector<map::IndexedKeyframe> exportEntries() const;
  void importEntries(const std::vector<map::IndexedKeyframe>& entries);
  map::DescriptorSettings descriptorSettings() const { return {config_.patch_size, config_.smoothing_sigma}; }
  std::size_t size() const { return entries_.size(); }
  const RelocalizerConfig& config() const { return config_; }

 private:
  struct Point {
    std::uint64_t landmark_id;
    Eigen::Vector3d p_w;
    tracking::BriefDescriptor descriptor;
    signed char polarity;
  };
  struct Entry {
    std::uint32_t serial;  // key of the entry in the hash tables
    std::uint64_t frame_index;
    Eigen::Isometry3d T_w_c;
    std::vector<Point> points;
    std::vector<tracking::BriefDescriptor> descriptors;  // of points, for matching
    std::vector<signed char> polarities;
  };
  static constexpr int kTables = 4;
  static constexpr int kKeyBits = 16;  // 15 descriptor bits and the curvature sign
  std::uint32_t key(int table, const tracking::BriefDescriptor& d, signed char polarity) const;
  void hashEntry(const Entry& e, bool insert);
  cv::Mat smooth(const cv::Mat& image) const;
  // The share of the newest entry's points that are among `landmarks` (the non-null ones; 0
  // without an entry): how much of what the index holds last the keyframe still sees.
  double sharedWithNewest(const std::vector<const map::Landmark*>& landmarks) const;
  // Indices of at most max_count of the tracks (restricted to `use`), spread over a grid.
  std::vector<std::size_t> spread(const FrameContext& frame, const std::vector<bool>& use, int max_count) const;

  RelocalizerConfig config_;
  camera::Camera camera_;
  geometry::PnpConfig pnp_;
  tracking::BriefExtractor brief_, brief_upside_down_;
  std::deque<Entry> entries_;
  std::uint32_t next_serial_ = 0;
  std::vector<std::array<int, kKeyBits - 1>> key_bits_;           // per table, the descriptor bits of its key
  std::vector<std::vector<std::vector<std::uint32_t>>> buckets_;  // [table][key] -> entry serials
};

}  // namespace vitamin_e::pipeline
