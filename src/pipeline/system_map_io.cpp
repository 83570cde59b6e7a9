// pipeline::System and the map file: the map's contents gathered from the
// stages' own interfaces (Map::snapshot, Relocalizer::exportEntries) and given
// back to them (Map::restore, Relocalizer::importEntries), and the
// localization-only mode.
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "system_impl.h"

namespace vitamin_e::pipeline {

namespace {

const char* const kScaleConvention =
    "monocular: 1 map unit = the median depth of the points of the first initialization, seen from its reference "
    "camera (no metric scale)";

std::string size(const camera::Camera& c) { return std::to_string(c.width()) + "x" + std::to_string(c.height()); }

// The loaded map must come from this camera: the size exactly, the pinhole
// intrinsics within 2 % (a recalibration, not another lens).
void checkCamera(const camera::Camera& map_camera, const camera::Camera& camera) {
  if (map_camera.width() != camera.width() || map_camera.height() != camera.height()) {
    throw std::invalid_argument("the map was made with a " + size(map_camera) + " camera, this camera is " +
                                size(camera));
  }
  auto off = [](double a, double b, double ref) { return std::abs(a - b) > 0.02 * ref; };
  if (off(map_camera.fx(), camera.fx(), camera.fx()) || off(map_camera.fy(), camera.fy(), camera.fy()) ||
      off(map_camera.cx(), camera.cx(), camera.width()) || off(map_camera.cy(), camera.cy(), camera.height())) {
    throw std::invalid_argument("the map was made with another camera (" + map_camera.describe() +
                                "), this camera is " + camera.describe());
  }
}

// Throws std::invalid_argument naming what makes the map file unusable here.
void checkLoadable(const map::MapFileContents& c, const camera::Camera& camera, bool relocalization_enabled,
                   const map::DescriptorSettings& mine) {
  checkCamera(c.camera, camera);
  if (!relocalization_enabled) {
    throw std::invalid_argument("relocalization.enabled is false: the camera could not be found in a loaded map");
  }
  if (c.descriptors.patch_size != mine.patch_size || c.descriptors.smoothing_sigma != mine.smoothing_sigma) {
    throw std::invalid_argument("the map's keyframes were described with relocalization.patch_size " +
                                std::to_string(c.descriptors.patch_size) + " and smoothing_sigma " +
                                std::to_string(c.descriptors.smoothing_sigma) + ", this configuration has " +
                                std::to_string(mine.patch_size) + " and " + std::to_string(mine.smoothing_sigma));
  }
  if (c.keyframe_index.empty()) {
    throw std::invalid_argument("the map has no indexed keyframe: the camera could not be found in it");
  }
  if (!(c.scene_depth > 0.0) || !std::isfinite(c.scene_depth)) {
    throw std::invalid_argument("the map's scene depth is not positive");
  }
}

// Frames and tracks go on after every index and id the map holds.
struct Numbering {
  std::uint64_t frame = 0;
  std::uint64_t track = 0;
};
Numbering numberingAfter(const map::MapFileContents& c) {
  Numbering next;
  auto frame = [&](std::uint64_t f) { next.frame = std::max(next.frame, f + 1); };
  auto track = [&](std::uint64_t id) { next.track = std::max(next.track, id + 1); };
  for (const map::Keyframe& kf : c.map.keyframes) {
    frame(kf.frame_index);
    for (const auto& o : kf.observations) track(o.first);
  }
  for (const map::Landmark& l : c.map.landmarks) {
    frame(l.last_seen_frame);
    track(l.id);
  }
  for (const map::DormantLandmark& d : c.map.dormant) track(d.id);
  for (const map::IndexedKeyframe& kf : c.keyframe_index) {
    frame(kf.frame_index);
    for (const map::IndexedPoint& p : kf.points) track(p.landmark_id);
  }
  return next;
}

}  // namespace

// A new map would discard the loaded one (and a later save would overwrite its
// file with the new map): with a loaded map the camera is only ever looked for in it.
bool System::Impl::keepRelocalizing() const { return localization_only || map_loaded; }

map::MapFileContents System::exportMap() const {
  const Impl& s = *impl_;
  map::MapFileContents c;
  c.camera = s.camera;
  c.scale_convention = kScaleConvention;
  c.scene_depth = s.scene_depth;
  c.descriptors = s.relocalizer.descriptorSettings();
  c.map = s.map.snapshot();
  c.keyframe_index = s.relocalizer.exportEntries();
  return c;
}

void System::loadMap(const map::MapFileContents& c) {
  Impl& s = *impl_;
  if (s.counters.frames_processed > 0 || s.front_end.frameIndexOffset() > 0) {
    throw std::invalid_argument("a map can only be loaded before the first frame");
  }
  checkLoadable(c, s.camera, s.config.relocalization.enabled, s.relocalizer.descriptorSettings());
  map::Map restored(s.config.map);
  restored.restore(c.map);  // throws, leaving this system as it was
  const Numbering next = numberingAfter(c);
  s.map = std::move(restored);
  s.relocalizer.importEntries(c.keyframe_index);
  s.front_end.continueNumbering(next.frame, next.track);
  s.initializer.reset();
  s.motion.invalidate();
  s.scene_depth = c.scene_depth;
  s.initialized_once = true;  // a later new map (extend mode, after a loss) starts at the last pose and scale
  s.recovery.startRelocalizing();
  s.map_loaded = true;
}

bool System::saveMap(const std::string& path, std::string* error) const {
  return map::saveMapFile(exportMap(), path, error);
}

bool System::mapLoaded() const { return impl_->map_loaded; }

void System::setLocalizationOnly(bool on) {
  impl_->localization_only = on;
  impl_->mapper.setLocalizationOnly(on);
}

bool System::localizationOnly() const { return impl_->localization_only; }

}  // namespace vitamin_e::pipeline
