#pragma once
// Configuration of the whole SLAM system: one struct per component with in-class
// defaults, loaded from one yaml file (config/euroc.yaml, ...) and validated at
// start-up. A bad value throws ConfigError with a message naming the key.
#include <stdexcept>
#include <string>

namespace vitamin_e::pipeline {

struct ConfigError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct SystemConfig;
// Reads a yaml config file; keys not present keep their defaults; unknown keys
// and bad values throw ConfigError.
SystemConfig loadSystemConfig(const std::string& yaml_path);

}  // namespace vitamin_e::pipeline

#include "vitamin_e/pipeline/system_config_types.h"
