#pragma once
// The fields of SystemConfig (see system_config.h).
#include <string>

namespace vitamin_e::pipeline {

struct SystemConfig {
  // Fields are added per component as the modules land (tracker, init, pnp, ba, map, mesh, tsdf).
  int min_init_tracks = 200;  // 2D tracks needed to attempt initialization

  void validate() const;        // throws ConfigError
  std::string describe() const; // readable listing of every value
};

}  // namespace vitamin_e::pipeline
