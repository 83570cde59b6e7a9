#pragma once
// The SLAM map: landmarks (3D points, keyed by the id of the 2D track that
// observes them) and keyframes (poses with the normalized observations of the
// tracks they saw). Bounded: keyframes beyond the window are retired and
// landmarks no longer observed are moved to a voxel-thinned archive kept for
// export. The archive is capped: when it fills up, its voxel doubles and it is
// thinned again, so memory stays bounded on long runs while every explored
// place keeps points (at a coarser spacing). Retired landmarks are also kept,
// with their ids, as dormant landmarks (a bounded FIFO) that a new track at the
// same place can be re-associated with (map reuse: the old, better anchored
// position is used again instead of a new, drifted triangulation).
#include <Eigen/Geometry>
#include <cstdint>
#include <deque>
#include <unordered_map>
#include <unordered_set>
#include <vector>

namespace vitamin_e::map {

// One keyframe's view of a landmark.
struct LandmarkObservation {
  std::uint64_t keyframe = 0;                    // frame index of the keyframe
  Eigen::Vector2d xy = Eigen::Vector2d::Zero();  // normalized undistorted
};

struct Landmark {
  std::uint64_t id = 0;  // the track id
  Eigen::Vector3d p_w = Eigen::Vector3d::Zero();
  std::uint8_t intensity = 0;
  std::int8_t polarity = 0;  // sign of the image curvature of its track (+1 / -1, 0 unknown)
  bool revived = false;      // re-associated from the dormant landmarks (its position predates the window)
  int num_observations = 0;  // keyframes that saw it (incl. retired ones)
  std::uint64_t last_seen_frame = 0;
  int outlier_count = 0;                          // times flagged by pose estimation / BA
  std::vector<LandmarkObservation> observations;  // by the active keyframes, oldest first
};

struct Keyframe {
  std::uint64_t frame_index = 0;
  double timestamp = 0.0;
  Eigen::Isometry3d T_w_c = Eigen::Isometry3d::Identity();
  // normalized undistorted observation (x/z, y/z) of each track seen
  std::unordered_map<std::uint64_t, Eigen::Vector2d> observations;
};

// A landmark that left the active window, kept for re-association.
struct DormantLandmark {
  std::uint64_t id = 0;  // its last track id
  Eigen::Vector3d p_w = Eigen::Vector3d::Zero();
  std::uint8_t intensity = 0;
  std::int8_t polarity = 0;
  int num_observations = 0;
  bool revived = false;  // taken back into the active map (the entry is then a tombstone)
};

// What a new landmark starts with (Map::addLandmark).
struct NewLandmark {
  std::uint64_t id = 0;  // the track id
  Eigen::Vector3d p_w = Eigen::Vector3d::Zero();
  std::uint8_t intensity = 0;
  std::int8_t polarity = 0;
  std::uint64_t seen_frame = 0;  // last frame its track was seen in
  int prior_observations = 0;    // keyframe observations it had before the active window
};

struct ArchivedPoint {
  Eigen::Vector3d p_w;
  std::uint8_t intensity;
};

// The map's state as plain data (Map::snapshot / Map::restore), e.g. for the
// map file. Landmark observations are not part of it: they are the keyframes'
// observations of the landmark's track, rebuilt on restore.
struct MapSnapshot {
  std::vector<Keyframe> keyframes;       // the active window, oldest first
  std::vector<Landmark> landmarks;       // by id; `observations` left empty
  std::vector<DormantLandmark> dormant;  // in retirement order
  std::uint64_t dormant_dropped = 0;
  std::vector<ArchivedPoint> archive;
  double archive_voxel = 0.0;
};

struct MapConfig {
  int max_keyframes = 10;  // keyframes kept in the active window
  // true: a full window retires the keyframe whose removal costs the newest keyframe's points
  // least parallax (the widest angle between two rays of the keyframes observing a point): one
  // that sees none of them (left behind at speed) or one crowded between its neighbours (a turn
  // makes a keyframe per frame); never one of the newest keep_newest_keyframes. false: the
  // oldest leaves (euroc.yaml: on a drone's whole render the parallax rule cost accuracy).
  bool retire_least_parallax = true;
  // Experimental, with retire_least_parallax: what a keyframe's removal costs is the number of the
  // newest keyframe's points that rely on it (without it their widest angle is less than half),
  // not the angle they lose. Off: not yet better on every camera (docs/ROBUSTNESS.md).
  bool retire_fewest_reliant = false;
  // Experimental, with retire_least_parallax: the oldest keyframe leaves unless the current points
  // it anchors (it is one end of their widest pair) would lose more than anchor_loss_share of
  // their summed angle without it; then the cheapest leaves, as above. Off: it holds a drone's
  // render but is oldest-first on KITTI (docs/ROBUSTNESS.md).
  bool retire_oldest_unless_anchor = false;
  double anchor_loss_share = 0.5;  // in [0, 1]
  // Experimental, with retire_least_parallax: the oldest keyframe leaves whenever the window spans
  // more than this many frames (0: never). Tests whether a drone's window suffers from keyframes
  // kept too long for their baselines (docs/ROBUSTNESS.md); the count depends on the frame rate.
  int retire_oldest_beyond_frames = 0;  // >= 0
  int keep_newest_keyframes = 3;        // >= 1
  double archive_voxel_m = 0.0;         // 0: archive every retired landmark; >0: one per voxel (map units)
  // Cap on archived points (~70 B each with the voxel index). Reaching it
  // doubles the voxel (from 1/2048 of the archive's extent when it was 0) and
  // re-thins the archive to at most half the cap.
  std::size_t max_archive_points = 300000;
  int min_observations_to_archive = 3;  // fewer keyframe observations: a retired landmark is dropped
  // Retired landmarks kept for re-association (~60 B each); the oldest go first.
  // 0 turns map reuse from dormant landmarks off.
  std::size_t max_dormant_landmarks = 100000;
  void validate() const;  // throws std::invalid_argument
};

class Map {
 public:
  explicit Map(const MapConfig& config = {});

  void clear();  // drops active keyframes and landmarks (archive kept)

  // Everything but the configuration, as plain data; ids sorted so that equal
  // maps give equal snapshots.
  MapSnapshot snapshot() const;
  // Replaces the whole state with the snapshot's (under this map's config:
  // keyframes beyond max_keyframes are retired, oldest first). Throws
  // std::invalid_argument, leaving the map as it was, when the snapshot is
  // inconsistent (keyframes out of order, duplicate ids, non-finite values).
  void restore(const MapSnapshot& snapshot);

  // Read access. The map keeps its invariants (observations on both sides,
  // orphans, the archive): every change goes through the methods below.
  const Landmark* landmark(std::uint64_t id) const;
  const std::unordered_map<std::uint64_t, Landmark>& landmarks() const { return landmarks_; }
  const std::deque<Keyframe>& keyframes() const { return keyframes_; }

  // Adds (or replaces) a landmark and attaches the observations the active
  // keyframes have of its track.
  const Landmark& addLandmark(const NewLandmark& landmark);
  void removeLandmark(std::uint64_t id);  // bad point: dropped, not archived
  // The landmark leaves the active map as if retired (archived once, kept as a
  // dormant landmark a new track can take over): a map point whose track went
  // wrong while the map must not lose points (localization only).
  void detachLandmark(std::uint64_t id);
  void setLandmarkPosition(std::uint64_t id, const Eigen::Vector3d& p_w);
  void markSeen(std::uint64_t id, std::uint64_t frame_index);
  void markAllSeen(std::uint64_t frame_index);
  // Counts one more time the landmark was an outlier; returns the new count (0: no such landmark).
  int flagOutlier(std::uint64_t id);

  // Adds a keyframe (its observations are attached to the existing landmarks);
  // retires one beyond max_keyframes (which one: MapConfig::retire_least_parallax).
  // Landmarks that no active keyframe observes any more
  // and that were not seen since the retired keyframe's successor are archived
  // (if well observed) and removed.
  const Keyframe& addKeyframe(Keyframe keyframe);
  void setKeyframePose(std::size_t index, const Eigen::Isometry3d& T_w_c);  // index into keyframes()
  // A change of the map's scale: keyframe centres, landmarks and dormant landmarks
  // move to centre + factor (x - centre). The archive keeps the scale it was made
  // in (it is exported with the trajectory of its time). factor > 0.
  void rescale(const Eigen::Vector3d& centre_w, double factor);

  // Re-association (map reuse). relabelLandmark gives an active landmark whose
  // track ended the id of a new track seen at the same place: the keyframes'
  // observations move to the new id. reviveDormant brings dormant landmark
  // `index` back into the active map under `track_id`. Both mark the landmark
  // seen at frame_index and take the track's polarity when theirs is unknown.
  // Both return false (and change nothing) when the ids clash: the new id is a
  // landmark already, or a keyframe observed both tracks (they cannot be one point).
  bool relabelLandmark(std::uint64_t old_id, std::uint64_t new_id, std::uint64_t frame_index,
                       std::int8_t track_polarity = 0);
  bool reviveDormant(std::size_t index, std::uint64_t track_id, std::uint64_t frame_index,
                     std::int8_t track_polarity = 0);
  const std::deque<DormantLandmark>& dormant() const { return dormant_; }
  // Dormant landmarks ever dropped from the front (index i of dormant() is entry
  // number dormantDropped() + i in the order of retirement).
  std::uint64_t dormantDropped() const { return dormant_dropped_; }

  const std::vector<ArchivedPoint>& archive() const { return archive_; }
  double archiveVoxel() const { return archive_voxel_; }  // current thinning voxel (0: none yet)
  // Active landmarks followed by archived points.
  std::vector<ArchivedPoint> allPoints() const;

 private:
  void retireKeyframe(const Keyframe& keyframe, std::uint64_t next_keyframe);  // frame index of its successor
  std::size_t keyframeToRetire() const;           // index into keyframes_ (see MapConfig::retire_least_parallax)
  void retireLandmark(const Landmark& landmark);  // to the archive and the dormant landmarks
  void archive(const Landmark& landmark);
  void coarsenArchive();
  Landmark* find(std::uint64_t id);

  MapConfig config_;
  std::unordered_map<std::uint64_t, Landmark> landmarks_;
  std::deque<Keyframe> keyframes_;
  std::vector<std::uint64_t> orphans_;  // landmarks without keyframe observations, still tracked
  std::deque<DormantLandmark> dormant_;
  std::uint64_t dormant_dropped_ = 0;
  std::vector<ArchivedPoint> archive_;
  double archive_voxel_ = 0.0;
  std::unordered_set<std::uint64_t> archive_voxels_;  // occupied voxels at archive_voxel_
};

}  // namespace vitamin_e::map
