#pragma once
// A rosbag of sensor_msgs/Image as an io::Dataset (for the offline runner and
// tests): the image messages of one topic are indexed once at open (timestamps
// from header.stamp, sorted), images are decoded lazily by loadImage().
// Encodings: mono8, mono16, rgb8, bgr8, rgba8, bgra8. The calibration comes from
// a file (DatasetOptions::calibration_path), which is required.
#include <memory>
#include <string>

#include "vitamin_e/io/dataset.h"

namespace vitamin_e_ros {

class BagDataset : public vitamin_e::io::Dataset {
 public:
  // Throws io::DatasetError (one line) for a missing/unreadable/truncated bag, a
  // topic without images (the message lists the bag's image topics), a missing
  // or bad calibration, or a first image whose size differs from the calibration.
  BagDataset(const std::string& bag_path, const vitamin_e::io::DatasetOptions& options);
  ~BagDataset() override;

  std::string kind() const override { return "rosbag"; }
  std::size_t size() const override;
  double timestamp(std::size_t i) const override;
  // header.stamp as "sec.nsec" with 9 decimals (exact).
  std::string timestampText(std::size_t i) const override;
  cv::Mat loadImage(std::size_t i) const override;
  const vitamin_e::camera::CameraCalibration& calibration() const override;
  const std::string& topic() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// openDataset for folders and bags: a ".bag" file goes to BagDataset.
std::unique_ptr<vitamin_e::io::Dataset> openAnyDataset(const std::string& path,
                                                       const vitamin_e::io::DatasetOptions& options);

}  // namespace vitamin_e_ros
