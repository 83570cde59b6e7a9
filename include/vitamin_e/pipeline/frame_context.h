#pragma once
// The frame being mapped, handed from stage to stage as an argument: its tracks.
// The map point a track observes is looked up by the track's id in the map
// (map::Map::landmark) when a stage needs it, never cached across a change of the map.
#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "vitamin_e/pipeline/tracked_frame.h"

namespace vitamin_e::pipeline {

struct FrameContext {
  std::uint64_t frame_index = 0;
  double timestamp = 0.0;
  std::string timestamp_text;
  std::vector<FrameTrack> tracks;
  cv::Mat image;  // the input image (mono8, shared)
};

}  // namespace vitamin_e::pipeline
