#include "vitamin_e/map/map_file.h"

#include <algorithm>
#include <cstdio>
#include <set>

#include "vitamin_e/common/binary_file.h"

namespace vitamin_e::map {

namespace {

constexpr std::uint32_t kByteOrderMark = 0x01020304u;
constexpr std::uint32_t kEndMark = 0x454e444du;  // "MDNE": the payload ended where the writer ended it
const char* const kMagic = "vitamin_e map v";

std::size_t distinctKeyframes(const MapFileContents& c) {
  std::set<std::uint64_t> ids;
  for (const Keyframe& kf : c.map.keyframes) ids.insert(kf.frame_index);
  for (const IndexedKeyframe& kf : c.keyframe_index) ids.insert(kf.frame_index);
  return ids.size();
}

std::size_t mapPoints(const MapFileContents& c) {
  std::size_t n = c.map.landmarks.size();
  for (const DormantLandmark& d : c.map.dormant) n += d.revived ? 0 : 1;
  return n;
}

void putPose(BinaryWriter& w, const Eigen::Isometry3d& T) {
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) w.put(T.matrix()(r, c));
  }
}

Eigen::Isometry3d getPose(BinaryReader& r, const std::string& what) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  for (int i = 0; i < 3; ++i) {
    for (int c = 0; c < 4; ++c) T.matrix()(i, c) = r.getFinite("pose value");
  }
  const Eigen::Matrix3d R = T.linear();
  if ((R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() > 1e-6 || R.determinant() <= 0.0) {
    r.fail(what + " has a pose that is not a rotation and translation");
  }
  return T;
}

void putVector(BinaryWriter& w, const Eigen::Vector3d& p) { w.putDoubles(p.data(), 3); }

Eigen::Vector3d getVector(BinaryReader& r) {
  Eigen::Vector3d p;
  for (int k = 0; k < 3; ++k) p[k] = r.getFinite("position");
  return p;
}

std::int8_t getPolarity(BinaryReader& r) {
  const std::int8_t p = r.get<std::int8_t>();
  if (p < -1 || p > 1) r.fail("a curvature sign of " + std::to_string(p));
  return p;
}

bool getFlag(BinaryReader& r) {
  const std::uint8_t b = r.get<std::uint8_t>();
  if (b > 1) r.fail("a flag of " + std::to_string(b));
  return b == 1;
}

std::string payloadOf(const MapFileContents& c) {
  BinaryWriter w;
  w.put(kByteOrderMark);
  // Camera.
  const camera::Camera& cam = c.camera;
  w.put(static_cast<std::int32_t>(cam.width()));
  w.put(static_cast<std::int32_t>(cam.height()));
  w.put(cam.fx());
  w.put(cam.fy());
  w.put(cam.cx());
  w.put(cam.cy());
  w.put(static_cast<std::uint8_t>(cam.model()));
  w.put(static_cast<std::uint32_t>(cam.distortion().size()));
  w.putDoubles(cam.distortion().data(), cam.distortion().size());
  // Scale and descriptors.
  w.putString(c.scale_convention);
  w.put(c.scene_depth);
  w.put(static_cast<std::int32_t>(c.descriptors.patch_size));
  w.put(c.descriptors.smoothing_sigma);
  // Keyframe window, observations sorted by track id.
  w.put(static_cast<std::uint64_t>(c.map.keyframes.size()));
  std::vector<std::pair<std::uint64_t, Eigen::Vector2d>> obs;
  for (const Keyframe& kf : c.map.keyframes) {
    w.put(kf.frame_index);
    w.put(kf.timestamp);
    putPose(w, kf.T_w_c);
    obs.assign(kf.observations.begin(), kf.observations.end());
    std::sort(obs.begin(), obs.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    w.put(static_cast<std::uint64_t>(obs.size()));
    for (const auto& o : obs) {
      w.put(o.first);
      w.put(o.second.x());
      w.put(o.second.y());
    }
  }
  // Landmarks (snapshot order: by id).
  w.put(static_cast<std::uint64_t>(c.map.landmarks.size()));
  for (const Landmark& l : c.map.landmarks) {
    w.put(l.id);
    putVector(w, l.p_w);
    w.put(l.intensity);
    w.put(l.polarity);
    w.put(static_cast<std::uint8_t>(l.revived ? 1 : 0));
    w.put(static_cast<std::int32_t>(l.num_observations));
    w.put(l.last_seen_frame);
    w.put(static_cast<std::int32_t>(l.outlier_count));
  }
  // Dormant landmarks.
  w.put(c.map.dormant_dropped);
  w.put(static_cast<std::uint64_t>(c.map.dormant.size()));
  for (const DormantLandmark& d : c.map.dormant) {
    w.put(d.id);
    putVector(w, d.p_w);
    w.put(d.intensity);
    w.put(d.polarity);
    w.put(static_cast<std::int32_t>(d.num_observations));
    w.put(static_cast<std::uint8_t>(d.revived ? 1 : 0));
  }
  // Archive.
  w.put(c.map.archive_voxel);
  w.put(static_cast<std::uint64_t>(c.map.archive.size()));
  for (const ArchivedPoint& a : c.map.archive) {
    putVector(w, a.p_w);
    w.put(a.intensity);
  }
  // Relocalization index.
  w.put(static_cast<std::uint64_t>(c.keyframe_index.size()));
  for (const IndexedKeyframe& kf : c.keyframe_index) {
    w.put(kf.frame_index);
    putPose(w, kf.T_w_c);
    w.put(static_cast<std::uint64_t>(kf.points.size()));
    for (const IndexedPoint& p : kf.points) {
      w.put(p.landmark_id);
      putVector(w, p.p_w);
      for (std::uint64_t b : p.descriptor) w.put(b);
      w.put(p.polarity);
    }
  }
  w.put(kEndMark);
  return std::move(w.bytes());
}

// Smallest encoded sizes, to refuse counts the payload cannot hold.
constexpr std::size_t kKeyframeBytes = 8 + 8 + 96 + 8;
constexpr std::size_t kObservationBytes = 8 + 16;
constexpr std::size_t kLandmarkBytes = 8 + 24 + 3 + 4 + 8 + 4;
constexpr std::size_t kDormantBytes = 8 + 24 + 2 + 4 + 1;
constexpr std::size_t kArchivedBytes = 24 + 1;
constexpr std::size_t kIndexedKeyframeBytes = 8 + 96 + 8;
constexpr std::size_t kIndexedPointBytes = 8 + 24 + 32 + 1;

MapFileContents parsePayload(const std::string& payload, const std::string& what) {
  BinaryReader r(payload.data(), payload.size(), what);
  if (r.get<std::uint32_t>() != kByteOrderMark) r.fail("written with another byte order or damaged");
  MapFileContents c;
  const std::int32_t width = r.get<std::int32_t>();
  const std::int32_t height = r.get<std::int32_t>();
  const double fx = r.getFinite("fx"), fy = r.getFinite("fy"), cx = r.getFinite("cx"), cy = r.getFinite("cy");
  const std::uint8_t model = r.get<std::uint8_t>();
  if (model > static_cast<std::uint8_t>(camera::DistortionModel::kEquidistant)) {
    r.fail("unknown distortion model " + std::to_string(model));
  }
  const std::uint32_t num_distortion = r.get<std::uint32_t>();
  if (num_distortion > 16) r.fail(std::to_string(num_distortion) + " distortion coefficients");
  std::vector<double> distortion(num_distortion);
  for (double& d : distortion) d = r.getFinite("distortion coefficient");
  try {
    c.camera = camera::Camera(width, height, fx, fy, cx, cy, static_cast<camera::DistortionModel>(model), distortion);
  } catch (const camera::CalibrationError& e) {
    r.fail(std::string("bad camera calibration: ") + e.what());
  }
  c.scale_convention = r.getString(1024);
  c.scene_depth = r.getFinite("scene depth");
  if (!(c.scene_depth > 0.0)) r.fail("a scene depth of " + std::to_string(c.scene_depth));
  c.descriptors.patch_size = r.get<std::int32_t>();
  c.descriptors.smoothing_sigma = r.getFinite("descriptor smoothing");

  const std::uint64_t num_keyframes = r.getCount(kKeyframeBytes, "keyframes");
  c.map.keyframes.resize(num_keyframes);
  for (Keyframe& kf : c.map.keyframes) {
    kf.frame_index = r.get<std::uint64_t>();
    const std::string name = "keyframe " + std::to_string(kf.frame_index);
    kf.timestamp = r.getFinite("timestamp");
    kf.T_w_c = getPose(r, name);
    const std::uint64_t n = r.getCount(kObservationBytes, "observations");
    kf.observations.reserve(n);
    for (std::uint64_t i = 0; i < n; ++i) {
      const std::uint64_t id = r.get<std::uint64_t>();
      const double x = r.getFinite("observation"), y = r.getFinite("observation");
      if (!kf.observations.emplace(id, Eigen::Vector2d(x, y)).second)
        r.fail(name + " observes track " + std::to_string(id) + " twice");
    }
  }
  const std::uint64_t num_landmarks = r.getCount(kLandmarkBytes, "landmarks");
  c.map.landmarks.resize(num_landmarks);
  for (Landmark& l : c.map.landmarks) {
    l.id = r.get<std::uint64_t>();
    l.p_w = getVector(r);
    l.intensity = r.get<std::uint8_t>();
    l.polarity = getPolarity(r);
    l.revived = getFlag(r);
    l.num_observations = r.get<std::int32_t>();
    l.last_seen_frame = r.get<std::uint64_t>();
    l.outlier_count = r.get<std::int32_t>();
    if (l.num_observations < 0 || l.outlier_count < 0)
      r.fail("landmark " + std::to_string(l.id) + " has negative counts");
  }
  c.map.dormant_dropped = r.get<std::uint64_t>();
  const std::uint64_t num_dormant = r.getCount(kDormantBytes, "dormant landmarks");
  c.map.dormant.resize(num_dormant);
  for (DormantLandmark& d : c.map.dormant) {
    d.id = r.get<std::uint64_t>();
    d.p_w = getVector(r);
    d.intensity = r.get<std::uint8_t>();
    d.polarity = getPolarity(r);
    d.num_observations = r.get<std::int32_t>();
    d.revived = getFlag(r);
  }
  c.map.archive_voxel = r.getFinite("archive voxel");
  if (c.map.archive_voxel < 0.0) r.fail("a negative archive voxel");
  const std::uint64_t num_archived = r.getCount(kArchivedBytes, "archived points");
  c.map.archive.resize(num_archived);
  for (ArchivedPoint& a : c.map.archive) {
    a.p_w = getVector(r);
    a.intensity = r.get<std::uint8_t>();
  }
  const std::uint64_t num_indexed = r.getCount(kIndexedKeyframeBytes, "indexed keyframes");
  c.keyframe_index.resize(num_indexed);
  for (IndexedKeyframe& kf : c.keyframe_index) {
    kf.frame_index = r.get<std::uint64_t>();
    kf.T_w_c = getPose(r, "indexed keyframe " + std::to_string(kf.frame_index));
    const std::uint64_t n = r.getCount(kIndexedPointBytes, "indexed points");
    kf.points.resize(n);
    for (IndexedPoint& p : kf.points) {
      p.landmark_id = r.get<std::uint64_t>();
      p.p_w = getVector(r);
      for (std::uint64_t& b : p.descriptor) b = r.get<std::uint64_t>();
      p.polarity = getPolarity(r);
    }
  }
  if (r.get<std::uint32_t>() != kEndMark) r.fail("damaged (no end mark after the data)");
  if (r.remaining() != 0) r.fail(std::to_string(r.remaining()) + " bytes after the end mark");
  return c;
}

}  // namespace

std::string mapFileHeader(const MapFileContents& c) {
  char line[256];
  std::snprintf(line, sizeof(line), "vitamin_e map v%d, %zu keyframes, %zu points, camera %dx%d", kMapFileVersion,
                distinctKeyframes(c), mapPoints(c), c.camera.width(), c.camera.height());
  return line;
}

bool saveMapFile(const MapFileContents& contents, const std::string& path, std::string* error) {
  if (!contents.camera.valid()) {
    if (error) *error = "cannot write map '" + path + "': no camera calibration";
    return false;
  }
  return writeBinaryFile(path, mapFileHeader(contents), payloadOf(contents), error);
}

MapFileContents loadMapFile(const std::string& path) {
  const std::string what = "map file '" + path + "'";
  try {
    const BinaryFileContents file = readBinaryFile(path, kMagic, "map", kMapFileVersion);
    MapFileContents c = parsePayload(file.payload, what);
    const std::string expected = mapFileHeader(c);
    if (file.header_line != expected) {
      throw MapFileError(what + ": the header line '" + file.header_line + "' does not describe its data ('" +
                         expected + "')");
    }
    return c;
  } catch (const BinaryFileError& e) {
    throw MapFileError(e.what());
  }
}

}  // namespace vitamin_e::map
