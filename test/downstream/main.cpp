// Uses the installed core: a SLAM system on the default config, fed a textured image, and a
// generated message header (vitamin_e/TrackingStatus.h). Prints one line; exit 0 when it ran.
#include <cstdio>

#include <opencv2/core.hpp>

#include "vitamin_e/TrackingStatus.h"
#include "vitamin_e/pipeline/system.h"

int main() {
  vitamin_e::pipeline::SystemConfig config;
  config.validate();
  const vitamin_e::camera::Camera camera(160, 120, 150.0, 150.0, 79.5, 59.5);
  vitamin_e::pipeline::System slam(config, camera);
  cv::Mat image(120, 160, CV_8UC1);
  cv::randu(image, 0, 255);
  const auto result = slam.process(image, 1.0);
  vitamin_e::TrackingStatus status;
  status.frames_processed = slam.framesProcessed();
  std::printf("downstream: frame %lu %s, %lu processed\n", static_cast<unsigned long>(result.frame_index),
              vitamin_e::pipeline::toString(result.state), static_cast<unsigned long>(status.frames_processed));
  return status.frames_processed == 1 ? 0 : 1;
}
