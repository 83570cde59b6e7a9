#pragma once
// The tracking nodelet's trajectory file (issue 15, item 4): one TUM file, poses in the
// published map frame, in segments. A segment ends when the SLAM is restarted (~reset, a
// stamp jumping back, e.g. a bag played with --loop): each segment has its own map.
//   # timestamp tx ty tz qx qy qz qw (T_map_c, ...)
//   # segment 1: <why it started>
//   <t> <tx> ... <qw>
//   # segment 2: reset: stamp jumped back by 2.950 s
//   ...
// TUM readers skip the '#' lines, so a one-segment file reads as a plain trajectory.
#include <string>
#include <vector>

#include "vitamin_e/pipeline/system.h"

namespace vitamin_e_ros {

struct TrajectorySegment {
  std::string note;                                         // why it started (one line)
  std::vector<vitamin_e::pipeline::TrajectoryEntry> poses;  // T_map_c, time order
};

// Returns false (and sets *error) when the file cannot be written. Non-finite poses are skipped.
bool saveSegmentsTum(const std::vector<TrajectorySegment>& segments, const std::string& header, const std::string& path,
                     std::string* error);
// Reads such a file back (a file without segment lines is one segment). Throws std::runtime_error.
std::vector<TrajectorySegment> readSegmentsTum(const std::string& path);

}  // namespace vitamin_e_ros
