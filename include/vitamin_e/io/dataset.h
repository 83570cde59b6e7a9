#pragma once
// Offline dataset readers: EuRoC ASL folders, TUM RGB-D folders, KITTI odometry
// folders (and rosbags, through the ROS layer: vitamin_e/ros/bag_dataset.h).
// A Dataset is an indexed list of frames: timestamps are read at open, images
// are loaded lazily by loadImage(i).
#include <cstddef>
#include <memory>
#include <stdexcept>
#include <string>

#include <opencv2/core.hpp>

#include "vitamin_e/camera/camera.h"

namespace vitamin_e::io {

struct DatasetError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

class Dataset {
 public:
  virtual ~Dataset() = default;
  virtual std::string kind() const = 0;  // "euroc", "tum", "kitti", "rosbag"
  virtual std::size_t size() const = 0;
  virtual double timestamp(std::size_t i) const = 0;  // seconds
  // Seconds exactly as the dataset gives them (EuRoC ns 1403715273262142976 ->
  // "1403715273.262142976", by string manipulation, no rounding).
  virtual std::string timestampText(std::size_t i) const = 0;
  // CV_8UC1; converts rgb/bgr/16-bit; throws DatasetError naming the file if unreadable.
  virtual cv::Mat loadImage(std::size_t i) const = 0;
  virtual const camera::CameraCalibration& calibration() const = 0;
  // A ground-truth file found beside the data, if any.
  virtual std::string groundTruthPath() const { return {}; }
};

struct DatasetOptions {
  std::string calibration_path;  // overrides the dataset's own calibration
  std::string bag_topic = "/cam0/image_raw";
};

// "euroc" | "tum" | "kitti" | "rosbag" | "" (unknown).
std::string detectDatasetKind(const std::string& path);
// Folders only (bags: vitamin_e/ros/bag_dataset.h). Throws DatasetError with one clear line.
std::unique_ptr<Dataset> openDataset(const std::string& path, const DatasetOptions& options = {});

// Helpers shared by the readers (and the bag reader).
// Nanoseconds text -> seconds text ("1403715273262142976" -> "1403715273.262142976");
// throws DatasetError if not all digits.
std::string nanosecondsToSecondsText(const std::string& ns);
// Channel order of a colour image: OpenCV's (imread, imdecode) or an RGB(A) message.
enum class ChannelOrder { kBgr, kRgb };
// The one mono8 conversion (folders, bags, ROS messages): an 8- or 16-bit image with 1, 3
// or 4 channels -> CV_8UC1. Colour -> gray with OpenCV's weights, 16-bit -> scaled by 1/256.
// An 8-bit single-channel image is returned as it is (shared, not copied). Empty stays empty.
// Throws DatasetError for another depth or channel count.
cv::Mat toGray8(const cv::Mat& image, ChannelOrder order = ChannelOrder::kBgr);

}  // namespace vitamin_e::io
