// SystemConfig: yaml loading, validation and printing, all from one table of
// fields so the three can never disagree.
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <functional>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <type_traits>
#include <vector>

#include "vitamin_e/pipeline/system_config.h"

namespace vitamin_e::pipeline {

namespace {

struct Field {
  std::string section;
  std::string key;
  std::function<void(const YAML::Node&)> read;
  std::function<std::string()> print;
};

template <typename T>
Field field(const std::string& section, const std::string& key, T* value) {
  Field f;
  f.section = section;
  f.key = key;
  f.read = [value, section, key](const YAML::Node& node) {
    try {
      if constexpr (std::is_same_v<T, bool>) {
        *value = node.as<bool>();
      } else if constexpr (std::is_integral_v<T>) {
        const double d = node.as<double>();
        if (!std::isfinite(d) || std::floor(d) != d) throw std::runtime_error("not an integer");
        if (std::is_unsigned_v<T> && d < 0) throw std::runtime_error("must not be negative");
        if (d < static_cast<double>(std::numeric_limits<T>::lowest()) ||
            d >= std::ldexp(1.0, std::numeric_limits<T>::digits)) {
          throw std::runtime_error("out of range");
        }
        *value = static_cast<T>(d);
      } else {
        const double d = node.as<double>();
        if (!std::isfinite(d)) throw std::runtime_error("not finite");
        *value = static_cast<T>(d);
      }
    } catch (const std::exception& e) {
      throw ConfigError(section + "." + key + ": bad value '" + YAML::Dump(node) + "' (" + e.what() + ")");
    }
  };
  f.print = [value]() {
    std::ostringstream os;
    os << *value;
    return os.str();
  };
  return f;
}

std::vector<Field> fields(SystemConfig& c) {
  std::vector<Field> f;
  // tracker
  auto& t = c.tracker;
  f.push_back(field("tracker", "max_points", &t.max_points));
  f.push_back(field("tracker", "grid_cell_px", &t.grid_cell_px));
  f.push_back(field("tracker", "max_per_cell", &t.max_per_cell));
  f.push_back(field("tracker", "nms_radius_px", &t.nms_radius_px));
  f.push_back(field("tracker", "border_px", &t.border_px));
  f.push_back(field("tracker", "smoothing_sigma", &t.smoothing_sigma));
  f.push_back(field("tracker", "min_curvature", &t.min_curvature));
  f.push_back(field("tracker", "min_abs_curvature", &t.min_abs_curvature));
  f.push_back(field("tracker", "brief_scale", &t.brief_scale));
  f.push_back(field("tracker", "brief_max_keypoints", &t.brief_max_keypoints));
  f.push_back(field("tracker", "brief_patch_size", &t.brief_patch_size));
  f.push_back(field("tracker", "brief_max_distance", &t.brief_max_distance));
  f.push_back(field("tracker", "brief_ratio", &t.brief_ratio));
  f.push_back(field("tracker", "flow_sigma_px", &t.flow_sigma_px));
  f.push_back(field("tracker", "flow_sigma_start_px", &t.flow_sigma_start_px));
  f.push_back(field("tracker", "flow_iterations", &t.flow_iterations));
  f.push_back(field("tracker", "flow_min_matches", &t.flow_min_matches));
  f.push_back(field("tracker", "lambda", &t.lambda));
  f.push_back(field("tracker", "track_sigma_px", &t.track_sigma_px));
  f.push_back(field("tracker", "max_climb_steps", &t.max_climb_steps));
  f.push_back(field("tracker", "fb_threshold_px", &t.fb_threshold_px));
  f.push_back(field("tracker", "min_track_curvature", &t.min_track_curvature));
  f.push_back(field("tracker", "noise_reference", &t.noise_reference));
  f.push_back(field("tracker", "min_track_sharpness", &t.min_track_sharpness));
  f.push_back(field("tracker", "relative_strength_change", &t.relative_strength_change));
  f.push_back(field("tracker", "strength_ratio_min_change", &t.strength_ratio_min_change));
  f.push_back(field("tracker", "floor_follows_exposure", &t.floor_follows_exposure));
  f.push_back(field("tracker", "strength_at_subpixel_peak", &t.strength_at_subpixel_peak));
  f.push_back(field("tracker", "extremum_weight", &t.extremum_weight));
  f.push_back(field("tracker", "align_radius_px", &t.align_radius_px));
  f.push_back(field("tracker", "align_gain", &t.align_gain));
  f.push_back(field("tracker", "align_gain_min_change", &t.align_gain_min_change));
  f.push_back(field("tracker", "max_align_disagreement_px", &t.max_align_disagreement_px));
  f.push_back(field("tracker", "confirm_max_unaligned_fraction", &t.confirm_max_unaligned_fraction));
  f.push_back(field("tracker", "threads", &t.threads));
  // triangulation
  auto& tr = c.triangulation;
  f.push_back(field("triangulation", "min_parallax_deg", &tr.min_parallax_deg));
  f.push_back(field("triangulation", "max_reproj_error_px", &tr.max_reproj_error_px));
  f.push_back(field("triangulation", "min_depth", &tr.min_depth));
  f.push_back(field("triangulation", "gn_iterations", &tr.gn_iterations));
  // ba (subspace Gauss-Newton)
  auto& b = c.ba;
  f.push_back(field("ba", "robust_sigma_px", &b.robust_sigma_px));
  f.push_back(field("ba", "max_sweeps", &b.max_sweeps));
  f.push_back(field("ba", "tolerance", &b.tolerance));
  f.push_back(field("ba", "threads", &b.threads));
  f.push_back(field("ba", "use_schur", &b.use_schur));
  f.push_back(field("ba", "camera_iterations", &b.camera_iterations));
  f.push_back(field("ba", "camera_gs_tolerance", &b.camera_gs_tolerance));
  f.push_back(field("ba", "initial_lambda", &b.initial_lambda));
  f.push_back(field("ba", "max_retries", &b.max_retries));
  f.push_back(field("ba", "point_iterations", &b.point_iterations));
  // map
  auto& m = c.map;
  f.push_back(field("map", "max_keyframes", &m.max_keyframes));
  f.push_back(field("map", "archive_voxel_m", &m.archive_voxel_m));
  f.push_back(field("map", "max_archive_points", &m.max_archive_points));
  f.push_back(field("map", "min_observations_to_archive", &m.min_observations_to_archive));
  f.push_back(field("map", "max_dormant_landmarks", &m.max_dormant_landmarks));
  // dense reconstruction (map units)
  auto& d = c.dense;
  f.push_back(field("dense", "enabled", &c.dense_enabled));
  f.push_back(field("dense", "denoise", &d.denoise));
  f.push_back(field("dense", "min_points", &d.min_points));
  f.push_back(field("dense", "max_edge_px", &d.prune.max_edge_px));
  f.push_back(field("dense", "max_normal_angle_deg", &d.prune.max_normal_angle_deg));
  f.push_back(field("dense", "max_inv_depth_jump", &d.prune.max_inv_depth_jump));
  f.push_back(field("dense", "nltgv_iterations", &d.nltgv.iterations));
  f.push_back(field("dense", "nltgv_warm_iterations", &d.nltgv.warm_iterations));
  f.push_back(field("dense", "nltgv_lambda", &d.nltgv.lambda));
  f.push_back(field("dense", "voxel_size", &d.integrator.tsdf.voxel_size));
  f.push_back(field("dense", "truncation", &d.integrator.tsdf.truncation));
  f.push_back(field("dense", "max_weight", &d.integrator.tsdf.max_weight));
  f.push_back(field("dense", "min_depth", &d.integrator.tsdf.min_depth));
  f.push_back(field("dense", "max_depth", &d.integrator.tsdf.max_depth));
  f.push_back(field("dense", "min_extract_weight", &d.integrator.tsdf.min_extract_weight));
  f.push_back(field("dense", "raster_downscale", &d.integrator.tsdf.raster_downscale));
  f.push_back(field("dense", "asynchronous", &d.integrator.asynchronous));
  f.push_back(field("dense", "queue_capacity", &d.integrator.queue_capacity));
  f.push_back(field("dense", "block_when_full", &d.integrator.block_when_full));
  // pipeline
  f.push_back(field("pipeline", "min_init_tracks", &c.min_init_tracks));
  f.push_back(field("pipeline", "init_min_disparity_px", &c.init_min_disparity_px));
  f.push_back(field("pipeline", "init_max_pending_frames", &c.init_max_pending_frames));
  f.push_back(field("pipeline", "min_pose_inliers", &c.min_pose_inliers));
  f.push_back(field("pipeline", "min_pose_inlier_ratio", &c.min_pose_inlier_ratio));
  f.push_back(field("pipeline", "max_outlier_count", &c.max_outlier_count));
  f.push_back(field("pipeline", "max_reprojection_px", &c.max_reprojection_px));
  f.push_back(field("pipeline", "ba_fixed_keyframes", &c.ba_fixed_keyframes));
  f.push_back(field("pipeline", "ba_keyframe_sweeps", &c.ba_keyframe_sweeps));
  f.push_back(field("pipeline", "ba_frame_sweeps", &c.ba_frame_sweeps));
  f.push_back(field("pipeline", "ba_free_keyframes", &c.ba_free_keyframes));
  f.push_back(field("pipeline", "keyframe_parallax_px", &c.keyframe_parallax_px));
  f.push_back(field("pipeline", "keyframe_min_mapped_ratio", &c.keyframe_min_mapped_ratio));
  f.push_back(field("pipeline", "max_step_depth_ratio", &c.max_step_depth_ratio));
  f.push_back(field("pipeline", "reuse_radius_px", &c.reuse_radius_px));
  f.push_back(field("pipeline", "reuse_occlusion_ratio", &c.reuse_occlusion_ratio));
  f.push_back(field("pipeline", "reuse_fix_revived", &c.reuse_fix_revived));
  f.push_back(field("pipeline", "reuse_dormant_per_frame", &c.reuse_dormant_per_frame));
  // init (two-view); focal_px is taken from the camera
  auto& in = c.init;
  f.push_back(field("init", "ransac_threshold_px", &in.ransac_threshold_px));
  f.push_back(field("init", "min_parallax_deg", &in.min_parallax_deg));
  f.push_back(field("init", "min_inlier_ratio", &in.min_inlier_ratio));
  f.push_back(field("init", "min_points", &in.min_points));
  f.push_back(field("init", "confidence", &in.confidence));
  f.push_back(field("init", "max_iterations", &in.max_iterations));
  f.push_back(field("init", "max_reproj_error_px", &in.max_reproj_error_px));
  f.push_back(field("init", "point_min_parallax_deg", &in.point_min_parallax_deg));
  f.push_back(field("init", "rotation_only_max_ratio", &in.rotation_only_max_ratio));
  f.push_back(field("init", "planar_min_ratio", &in.planar_min_ratio));
  f.push_back(field("init", "homography_min_gain", &in.homography_min_gain));
  f.push_back(field("init", "planar_distinct_deg", &in.planar_distinct_deg));
  f.push_back(field("init", "ambiguous_rival_ratio", &in.ambiguous_rival_ratio));
  f.push_back(field("init", "refuse_ambiguous", &in.refuse_ambiguous));
  f.push_back(field("init", "min_valid_ratio", &in.min_valid_ratio));
  // pnp; focal_px is taken from the camera
  auto& pn = c.pnp;
  f.push_back(field("pnp", "ransac_threshold_px", &pn.ransac_threshold_px));
  f.push_back(field("pnp", "confidence", &pn.confidence));
  f.push_back(field("pnp", "max_iterations", &pn.max_iterations));
  f.push_back(field("pnp", "min_inliers", &pn.min_inliers));
  f.push_back(field("pnp", "min_inlier_ratio", &pn.min_inlier_ratio));
  f.push_back(field("pnp", "robust_sigma_px", &pn.robust_sigma_px));
  f.push_back(field("pnp", "refine_iterations", &pn.refine_iterations));
  f.push_back(field("pnp", "guess_min_inlier_ratio", &pn.guess_min_inlier_ratio));
  // relocalization
  auto& r = c.relocalization;
  f.push_back(field("relocalization", "enabled", &r.enabled));
  f.push_back(field("relocalization", "max_frames", &r.max_frames));
  f.push_back(field("relocalization", "max_keyframes", &r.max_keyframes));
  f.push_back(field("relocalization", "points_per_keyframe", &r.points_per_keyframe));
  f.push_back(field("relocalization", "query_points", &r.query_points));
  f.push_back(field("relocalization", "candidates", &r.candidates));
  f.push_back(field("relocalization", "patch_size", &r.patch_size));
  f.push_back(field("relocalization", "smoothing_sigma", &r.smoothing_sigma));
  f.push_back(field("relocalization", "max_distance", &r.max_distance));
  f.push_back(field("relocalization", "ratio", &r.ratio));
  f.push_back(field("relocalization", "min_inliers", &r.min_inliers));
  f.push_back(field("relocalization", "min_inlier_ratio", &r.min_inlier_ratio));
  f.push_back(field("relocalization", "upside_down", &r.upside_down));
  return f;
}

}  // namespace

fusion::DenseMapperConfig defaultDenseConfig() {
  fusion::DenseMapperConfig d;
  d.integrator.tsdf.voxel_size = 0.02;
  d.integrator.tsdf.truncation = 0.10;  // 5 voxels: 3 leave holes at grazing angles
  d.integrator.tsdf.min_depth = 0.05;
  d.integrator.tsdf.max_depth = 10.0;
  d.mesher.min_depth = d.prune.min_depth = 0.05;
  d.mesher.max_depth = d.prune.max_depth = 10.0;
  d.integrator.block_when_full = true;  // offline: fuse every frame
  return d;
}

SystemConfig loadSystemConfig(const std::string& yaml_path) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(yaml_path);
  } catch (const YAML::BadFile&) {
    throw ConfigError("cannot read config file '" + yaml_path + "'");
  } catch (const YAML::Exception& e) {
    throw ConfigError("config file '" + yaml_path + "' is not valid yaml: " + e.what());
  }
  SystemConfig config;
  if (root.IsNull()) return config;
  if (!root.IsMap()) throw ConfigError("config file '" + yaml_path + "': expected a map of sections");
  std::vector<Field> table = fields(config);
  // A key must be a plain scalar ("? [a, b]" would escape as a yaml-cpp exception).
  auto key_name = [&](const YAML::Node& key) {
    if (!key.IsScalar()) {
      throw ConfigError(yaml_path + ": line " + std::to_string(key.Mark().line + 1) + ": a key must be a name");
    }
    return key.Scalar();
  };
  for (const auto& section : root) {
    const std::string name = key_name(section.first);
    if (!section.second.IsMap()) {
      throw ConfigError(yaml_path + ": section '" + name + "' must be a map of key: value");
    }
    for (const auto& kv : section.second) {
      const std::string key = key_name(kv.first);
      bool found = false;
      for (Field& f : table) {
        if (f.section == name && f.key == key) {
          try {
            f.read(kv.second);
          } catch (const ConfigError& e) {
            throw ConfigError(yaml_path + ": " + e.what());  // the file, as for every other error
          }
          found = true;
          break;
        }
      }
      if (!found) throw ConfigError(yaml_path + ": unknown parameter '" + name + "." + key + "'");
    }
  }
  try {
    config.validate();
  } catch (const ConfigError& e) {
    throw ConfigError(yaml_path + ": " + e.what());
  }
  return config;
}

void SystemConfig::validate() const {
  auto check = [](bool ok, const std::string& what) {
    if (!ok) throw ConfigError(what);
  };
  try {
    tracker.validate();
    init.validate();
    pnp.validate();
    triangulation.validate();
    ba.validate();
    dense.validate();
    map.validate();
    relocalization.validate();
  } catch (const ConfigError&) {
    throw;
  } catch (const std::exception& e) {
    throw ConfigError(e.what());
  }
  check(min_init_tracks >= 8, "pipeline.min_init_tracks must be >= 8");
  check(init_min_disparity_px >= 0.0, "pipeline.init_min_disparity_px must be >= 0");
  check(init_max_pending_frames >= 2, "pipeline.init_max_pending_frames must be >= 2");
  check(min_pose_inliers >= 6, "pipeline.min_pose_inliers must be >= 6");
  check(min_pose_inlier_ratio >= 0.0 && min_pose_inlier_ratio <= 1.0, "pipeline.min_pose_inlier_ratio must be in [0, 1]");
  check(max_outlier_count >= 1, "pipeline.max_outlier_count must be >= 1");
  check(max_reprojection_px > 0.0, "pipeline.max_reprojection_px must be > 0");
  check(ba_fixed_keyframes >= 1 && ba_fixed_keyframes < map.max_keyframes,
        "pipeline.ba_fixed_keyframes must be in [1, map.max_keyframes)");
  check(ba_keyframe_sweeps >= 1, "pipeline.ba_keyframe_sweeps must be >= 1");
  check(ba_frame_sweeps >= 1, "pipeline.ba_frame_sweeps must be >= 1");
  check(ba_free_keyframes >= 1, "pipeline.ba_free_keyframes must be >= 1");
  check(keyframe_parallax_px > 0.0, "pipeline.keyframe_parallax_px must be > 0");
  check(keyframe_min_mapped_ratio >= 0.0 && keyframe_min_mapped_ratio <= 1.0,
        "pipeline.keyframe_min_mapped_ratio must be in [0, 1]");
  check(max_step_depth_ratio > 0.0, "pipeline.max_step_depth_ratio must be > 0");
  check(reuse_radius_px >= 0.0 && reuse_radius_px <= 20.0, "pipeline.reuse_radius_px must be in [0, 20]");
  check(reuse_occlusion_ratio >= 1.0, "pipeline.reuse_occlusion_ratio must be >= 1");
  check(reuse_dormant_per_frame >= 1, "pipeline.reuse_dormant_per_frame must be >= 1");
}

std::string SystemConfig::describe() const {
  SystemConfig copy = *this;
  std::ostringstream os;
  std::string section;
  for (const Field& f : fields(copy)) {
    if (f.section != section) {
      section = f.section;
      os << section << ":\n";
    }
    os << "  " << f.key << ": " << f.print() << "\n";
  }
  return os.str();
}

}  // namespace vitamin_e::pipeline
