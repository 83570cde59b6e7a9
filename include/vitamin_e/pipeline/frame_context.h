#pragma once
// The frame being mapped, handed from stage to stage as an argument: its tracks
// and, per track, the map point it observes (if any).
#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "vitamin_e/map/map.h"
#include "vitamin_e/pipeline/tracked_frame.h"

namespace vitamin_e::pipeline {

struct FrameContext {
  std::uint64_t frame_index = 0;
  double timestamp = 0.0;
  std::string timestamp_text;
  std::vector<FrameTrack> tracks;
  cv::Mat image;  // the input image (mono8, shared)
  // Per track, its landmark or null. Pointers into the map: call lookup() after
  // every change of the map's landmarks before reading them again.
  std::vector<const map::Landmark*> landmarks;

  void lookup(const map::Map& map) {
    landmarks.resize(tracks.size());
    for (std::size_t i = 0; i < tracks.size(); ++i) landmarks[i] = map.landmark(tracks[i].id);
  }
  std::size_t numMapped() const {
    std::size_t n = 0;
    for (const map::Landmark* l : landmarks) n += l ? 1 : 0;
    return n;
  }
};

}  // namespace vitamin_e::pipeline
