// SystemConfig: yaml loading, validation, printing and the reference
// (docs/CONFIG.md), all from one table of fields (config_table.cpp) so that
// they can never disagree.
#include <yaml-cpp/yaml.h>

#include <functional>
#include <initializer_list>
#include <sstream>
#include <stdexcept>
#include <string_view>
#include <vector>

#include "config_table.h"
#include "vitamin_e/pipeline/system_config.h"

namespace vitamin_e::pipeline {

using detail::Field;

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

tracking::TrackerConfig defaultTrackerConfig() {
  tracking::TrackerConfig t;
  t.lambda = 2.0;
  t.max_align_disagreement_px = 0.0;
  t.extremum_weight = 0.5;
  t.align_radius_px = 3;
  t.strength_at_subpixel_peak = false;  // strength checks on kappa at the integer maximum
  return t;
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
  std::vector<Field> table = detail::configTable(config);
  // A key must be a plain scalar ("? [a, b]" would escape as a yaml-cpp exception).
  auto key_name = [&](const YAML::Node& key) {
    if (!key.IsScalar()) {
      throw ConfigError(yaml_path + ": line " + std::to_string(key.Mark().line + 1) + ": a key must be a name");
    }
    return key.Scalar();
  };
  // The messages of the loops below, built without a temporary per '+'.
  auto message = [](std::initializer_list<std::string_view> parts) {
    std::string m;
    for (std::string_view part : parts) m += part;
    return m;
  };
  for (const auto& section : root) {
    const std::string name = key_name(section.first);
    if (!section.second.IsMap()) {
      throw ConfigError(message({yaml_path, ": section '", name, "' must be a map of key: value"}));
    }
    for (const auto& kv : section.second) {
      const std::string key = key_name(kv.first);
      const Field* found = nullptr;
      for (Field& f : table) {
        if (f.section == name && f.key == key) {
          found = &f;
          break;
        }
      }
      if (!found) {
        throw ConfigError(
            message({yaml_path, ": unknown parameter '", name, ".", key, "' (docs/CONFIG.md lists them)"}));
      }
      if (!found->internal.empty()) {
        throw ConfigError(message({yaml_path, ": '", name, ".", key, "' cannot be set: ", found->internal}));
      }
      try {
        found->read(kv.second);
      } catch (const ConfigError& e) {
        throw ConfigError(yaml_path + ": " + e.what());  // the file, as for every other error
      }
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
  // The components name their field; the message gets the yaml section in front.
  auto component = [](const std::string& section, const std::function<void()>& check) {
    try {
      check();
    } catch (const std::exception& e) {
      const std::string what = e.what();
      throw ConfigError(what.rfind(section + ".", 0) == 0 ? what : section + ": " + what);
    }
  };
  component("tracker", [&] { tracker.validate(); });
  component("init", [&] { init.validate(); });
  component("pnp", [&] { pnp.validate(); });
  component("triangulation", [&] { triangulation.validate(); });
  component("ba", [&] { ba.validate(); });
  component("map", [&] { map.validate(); });
  component("relocalization", [&] { relocalization.validate(); });
  component("ground", [&] { ground.validate(); });
  component("dense", [&] { dense.validate(); });
  auto check = [](bool ok, const std::string& what) {
    if (!ok) throw ConfigError(what);
  };
  check(min_init_track_budget_fraction >= 0.0 && min_init_track_budget_fraction <= 1.0,
        "pipeline.min_init_track_budget_fraction must be in [0, 1]");
  check(init_min_disparity_px >= 0.0, "pipeline.init_min_disparity_px must be >= 0");
  check(init_max_pending_frames >= 2, "pipeline.init_max_pending_frames must be >= 2");
  check(min_pose_inliers >= 6, "pipeline.min_pose_inliers must be >= 6");
  check(min_pose_inlier_ratio >= 0.0 && min_pose_inlier_ratio <= 1.0,
        "pipeline.min_pose_inlier_ratio must be in [0, 1]");
  check(weak_pose_max_step_ratio >= 1.0,
        "pipeline.weak_pose_max_step_ratio must be >= 1 (1: weak poses are never kept)");
  check(weak_pose_min_survival_ratio >= 0.0 && weak_pose_min_survival_ratio <= 1.0,
        "pipeline.weak_pose_min_survival_ratio must be in [0, 1] (0: the track survival is not checked)");
  check(max_outlier_count >= 1, "pipeline.max_outlier_count must be >= 1");
  check(max_reprojection_px > 0.0, "pipeline.max_reprojection_px must be > 0");
  check(ba_fixed_keyframes >= 1 && ba_fixed_keyframes < map.max_keyframes,
        "pipeline.ba_fixed_keyframes must be in [1, map.max_keyframes)");
  check(ba_keyframe_sweeps >= 1, "pipeline.ba_keyframe_sweeps must be >= 1");
  check(ba_frame_sweeps >= 1, "pipeline.ba_frame_sweeps must be >= 1");
  check(ba_free_keyframes >= 1, "pipeline.ba_free_keyframes must be >= 1");
  check(ba_free_min_shared >= 0.0 && ba_free_min_shared <= 1.0, "pipeline.ba_free_min_shared must be in [0, 1]");
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
  for (const Field& f : detail::configTable(copy)) {
    if (f.section != section) {
      section = f.section;
      os << section << ":\n";
    }
    // Internal members as comments: the output stays a loadable config file.
    if (f.internal.empty()) {
      os << "  " << f.key << ": " << f.print() << "\n";
    } else {
      os << "  # " << f.key << ": set internally (" << f.internal << ")\n";
    }
  }
  return os.str();
}

std::vector<ConfigField> configFields(const SystemConfig& config) {
  SystemConfig copy = config;
  const char* base = reinterpret_cast<const char*>(&copy);
  std::vector<ConfigField> out;
  for (const Field& f : detail::configTable(copy)) {
    ConfigField c;
    c.section = f.section;
    c.key = f.key;
    c.value = f.print();
    c.description = f.doc;
    c.internal = f.internal;
    for (const void* p : f.members) c.offsets.push_back(static_cast<const char*>(p) - base);
    out.push_back(std::move(c));
  }
  return out;
}

std::string configReferenceMarkdown() {
  auto cell = [](const std::string& s) {
    std::string out;
    for (char ch : s) out += ch == '|' ? std::string("\\|") : std::string(1, ch);
    return out;
  };
  const std::vector<ConfigField> table = configFields(SystemConfig{});
  std::ostringstream os;
  os << "# Configuration reference\n\n"
        "<!-- Generated by `vitamin_e_run --print-config-markdown > docs/CONFIG.md` from the field table in\n"
        "src/pipeline/system_config.cpp; edit the table, not this file (test_pipeline_config fails when it is\n"
        "stale). -->\n\n"
        "One yaml file configures the SLAM: `vitamin_e_run --config FILE`, and `~config_file` of the ROS\n"
        "tracking and meshing nodelets (config/euroc.yaml, config/kitti.yaml, config/tum.yaml). It has the\n"
        "sections below; a key that is not given keeps the default shown here. An unknown key or a bad value\n"
        "stops the program with an error naming the file and the key. "
        "`vitamin_e_run --config FILE --print-config`\nprints every value in force, as a config file.\n\n"
        "Sections:";
  for (const detail::SectionInfo& s : detail::configSections()) os << " [" << s.name << "](#" << s.name << ")";
  os << "\n";
  for (const detail::SectionInfo& s : detail::configSections()) {
    os << "\n## " << s.name << "\n\n" << s.about << "\n\n| Key | Default | Meaning |\n|---|---|---|\n";
    std::vector<const ConfigField*> internal;
    for (const ConfigField& f : table) {
      if (f.section != s.name) continue;
      if (!f.internal.empty()) {
        internal.push_back(&f);
        continue;
      }
      os << "| `" << f.key << "` | " << cell(f.value) << " | " << cell(f.description) << " |\n";
    }
    if (!internal.empty()) {
      os << "\nSet internally, not keys:\n\n";
      for (const ConfigField* f : internal) os << "- `" << f->key << "`: " << f->internal << "\n";
    }
  }
  return os.str();
}

}  // namespace vitamin_e::pipeline
