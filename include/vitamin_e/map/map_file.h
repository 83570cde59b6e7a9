#pragma once
// The map file: everything a later run needs to find the camera in a map made
// before and to go on localizing in it or mapping it: the map's state
// (MapSnapshot: the keyframe window, landmarks, dormant landmarks, archive),
// the keyframes the relocalizer indexes (pose and the BRIEF descriptors of
// their mapped points), the camera calibration and the map's scale.
//
// Format (version 1): one text line a human can read,
//   vitamin_e map v1, N keyframes, M points, camera WxH
// (N: distinct keyframes of the window and the index, M: landmarks and dormant
// landmarks), then the payload size and its FNV-1a checksum (8 bytes each) and
// the binary payload (little-endian, fixed-width; common/binary_file.h).
// Written atomically (temporary file + rename). Reading checks the header, the
// size, the checksum, every count and every value, and that the header agrees
// with the payload: a damaged or foreign file gives a MapFileError naming the
// file and the problem.
#include <array>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "vitamin_e/camera/camera.h"
#include "vitamin_e/map/map.h"

namespace vitamin_e::map {

constexpr int kMapFileVersion = 1;

// A described map point of an indexed keyframe.
struct IndexedPoint {
  std::uint64_t landmark_id = 0;
  Eigen::Vector3d p_w = Eigen::Vector3d::Zero();  // its position when the keyframe was indexed
  std::array<std::uint64_t, 4> descriptor{};      // 256 BRIEF tests
  std::int8_t polarity = 0;                       // curvature sign of its track
};

// A keyframe as the relocalizer indexes it.
struct IndexedKeyframe {
  std::uint64_t frame_index = 0;
  Eigen::Isometry3d T_w_c = Eigen::Isometry3d::Identity();
  std::vector<IndexedPoint> points;
};

// How the index's descriptors were computed: a relocalizer with other settings
// cannot match them.
struct DescriptorSettings {
  int patch_size = 0;
  double smoothing_sigma = 0.0;
};

struct MapFileContents {
  camera::Camera camera;  // the calibration the map was made with
  // A monocular map has no metric scale: its unit is set by the first
  // initialization (see scale_convention). scene_depth is the median depth of
  // the map seen from the camera when it was saved, in map units.
  std::string scale_convention;
  double scene_depth = 1.0;
  DescriptorSettings descriptors;
  MapSnapshot map;
  std::vector<IndexedKeyframe> keyframe_index;  // oldest first
};

struct MapFileError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// "vitamin_e map v1, N keyframes, M points, camera WxH".
std::string mapFileHeader(const MapFileContents& contents);
// Writes the file atomically; false (and *error) when it cannot.
bool saveMapFile(const MapFileContents& contents, const std::string& path, std::string* error = nullptr);
// Reads and checks a map file; throws MapFileError ("map file 'PATH': what").
MapFileContents loadMapFile(const std::string& path);

}  // namespace vitamin_e::map
