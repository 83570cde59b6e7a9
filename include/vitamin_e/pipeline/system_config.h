#pragma once
// Configuration of the whole SLAM system: one struct per component with in-class
// defaults, loaded from one yaml file (config/euroc.yaml, ...) and validated at
// start-up. A bad value throws ConfigError with a message naming the key.
//
// One table of fields (system_config.cpp) does the loading, the printing
// (SystemConfig::describe, vitamin_e_run --print-config) and the reference
// (docs/CONFIG.md, vitamin_e_run --print-config-markdown); a test checks that
// it covers every member of every config struct.
#include <cstddef>
#include <stdexcept>
#include <string>
#include <vector>

namespace vitamin_e::pipeline {

struct ConfigError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct SystemConfig;
// Reads a yaml config file; keys not present keep their defaults; unknown keys
// and bad values throw ConfigError.
SystemConfig loadSystemConfig(const std::string& yaml_path);

// One row of the table: a yaml key (section.key), or a struct member that is
// set internally and has no key (internal says by what).
struct ConfigField {
  std::string section;
  std::string key;
  std::string value;        // as printed by describe()
  std::string description;  // one line
  std::string internal;     // non-empty: not settable from the yaml; how the member is set
  // Byte offsets in SystemConfig of the struct members the row sets (a key can
  // set several, e.g. dense.max_depth: the mesher's, the pruning's and the TSDF's).
  std::vector<std::ptrdiff_t> offsets;
};
// The table at the values of `config`.
std::vector<ConfigField> configFields(const SystemConfig& config);
// docs/CONFIG.md: every key with its default and description, by section.
std::string configReferenceMarkdown();

}  // namespace vitamin_e::pipeline

#include "vitamin_e/pipeline/system_config_types.h"
