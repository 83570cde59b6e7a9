#pragma once
// Internal to the io module: a dataset that is a list of image files with
// timestamps (EuRoC, TUM and KITTI folders all reduce to this).
#include <filesystem>
#include <string>
#include <vector>

#include "vitamin_e/io/dataset.h"

namespace vitamin_e::io::detail {

namespace fs = std::filesystem;

struct FrameFile {
  double t = 0.0;
  std::string t_text;
  std::string path;
};

class FolderDataset : public Dataset {
 public:
  FolderDataset(std::string kind, std::vector<FrameFile> frames, camera::CameraCalibration calibration,
                std::string ground_truth)
      : kind_(std::move(kind)),
        frames_(std::move(frames)),
        calibration_(std::move(calibration)),
        ground_truth_(std::move(ground_truth)) {}

  std::string kind() const override { return kind_; }
  std::size_t size() const override { return frames_.size(); }
  double timestamp(std::size_t i) const override { return frames_.at(i).t; }
  std::string timestampText(std::size_t i) const override { return frames_.at(i).t_text; }
  cv::Mat loadImage(std::size_t i) const override;
  const camera::CameraCalibration& calibration() const override { return calibration_; }
  std::string groundTruthPath() const override { return ground_truth_; }

 private:
  std::string kind_;
  std::vector<FrameFile> frames_;
  camera::CameraCalibration calibration_;
  std::string ground_truth_;
};

// Reads an image file as CV_8UC1; throws DatasetError naming the file.
cv::Mat readGray(const std::string& path);
// Loads a calibration, turning a CalibrationError into a DatasetError.
camera::CameraCalibration loadCalibrationFor(const std::string& path, int width, int height);
// Throws DatasetError naming both sizes if the image does not match the calibration.
void checkImageSize(const cv::Mat& image, const std::string& image_path, const camera::CameraCalibration& calib,
                    const std::string& calib_path);
// Text utilities.
std::string trim(const std::string& s);
bool parseDouble(const std::string& text, double* value);

std::unique_ptr<Dataset> openEuroc(const fs::path& path, const DatasetOptions& options);
std::unique_ptr<Dataset> openTum(const fs::path& path, const DatasetOptions& options);
std::unique_ptr<Dataset> openKitti(const fs::path& path, const DatasetOptions& options);
// The EuRoC cam0 folder for a path (top folder, mav0/ or mav0/cam0/), empty if none.
fs::path findEurocCamFolder(const fs::path& path);

}  // namespace vitamin_e::io::detail
