// Dataset helpers, layout detection and openDataset().
#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "folder_dataset.h"
#include "vitamin_e/io/png_gray.h"

namespace vitamin_e::io {

std::string nanosecondsToSecondsText(const std::string& ns) {
  if (ns.empty() || !std::all_of(ns.begin(), ns.end(), [](unsigned char c) { return std::isdigit(c); })) {
    throw DatasetError("timestamp '" + ns + "' is not a number of nanoseconds");
  }
  std::string digits = ns;
  if (digits.size() < 10) digits.insert(0, 10 - digits.size(), '0');
  std::string sec = digits.substr(0, digits.size() - 9);
  // No leading zeros in the integer part ("0000000001" -> "1").
  const std::size_t nz = sec.find_first_not_of('0');
  sec = nz == std::string::npos ? "0" : sec.substr(nz);
  return sec + "." + digits.substr(digits.size() - 9);
}

cv::Mat toGray8(const cv::Mat& image, ChannelOrder order) {
  if (image.empty()) return image;
  cv::Mat img = image;
  if (img.depth() == CV_16U) {
    img.convertTo(img, CV_8U, 1.0 / 256.0);
  } else if (img.depth() != CV_8U) {
    throw DatasetError("unsupported image depth (8 or 16 bit expected)");
  }
  const bool rgb = order == ChannelOrder::kRgb;
  cv::Mat gray;
  switch (img.channels()) {
    case 1: gray = img; break;
    case 3: cv::cvtColor(img, gray, rgb ? cv::COLOR_RGB2GRAY : cv::COLOR_BGR2GRAY); break;
    case 4: cv::cvtColor(img, gray, rgb ? cv::COLOR_RGBA2GRAY : cv::COLOR_BGRA2GRAY); break;
    default: throw DatasetError("unsupported number of image channels: " + std::to_string(img.channels()));
  }
  return gray;
}

namespace detail {

cv::Mat readGray(const std::string& path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) throw DatasetError("cannot read image '" + path + "' (file missing)");
  // The datasets' own images (8-bit grey PNG) decode here, 2-3x faster than through cv::imread;
  // every other image, and a damaged one, goes to cv::imread.
  std::ifstream file(path, std::ios::binary);
  std::uint8_t head[8] = {};
  if (file.read(reinterpret_cast<char*>(head), sizeof(head)) && hasPngSignature(head, sizeof(head))) {
    file.seekg(0, std::ios::end);
    const std::streamoff size = file.tellg();
    std::vector<std::uint8_t> bytes(size > 0 ? static_cast<std::size_t>(size) : 0);
    file.seekg(0);
    cv::Mat gray;
    if (file.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(bytes.size())) &&
        decodeGrayPng(bytes.data(), bytes.size(), &gray)) {
      return gray;
    }
  }
  cv::Mat raw;
  try {
    raw = cv::imread(path, cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception& e) {
    throw DatasetError("cannot read image '" + path + "': " + e.what());
  }
  if (raw.empty()) throw DatasetError("cannot read image '" + path + "' (corrupt or not an image)");
  try {
    return toGray8(raw);
  } catch (const DatasetError& e) {
    throw DatasetError("image '" + path + "': " + e.what());
  }
}

cv::Mat FolderDataset::loadImage(std::size_t i) const {
  const FrameFile& f = frames_.at(i);
  cv::Mat img = readGray(f.path);
  if (img.cols != calibration_.camera.width() || img.rows != calibration_.camera.height()) {
    throw DatasetError("image '" + f.path + "' is " + std::to_string(img.cols) + "x" + std::to_string(img.rows) +
                       ", the other images are " + std::to_string(calibration_.camera.width()) + "x" +
                       std::to_string(calibration_.camera.height()));
  }
  return img;
}

camera::CameraCalibration loadCalibrationFor(const std::string& path, int width, int height) {
  try {
    return camera::loadCalibration(path, width, height);
  } catch (const camera::CalibrationError& e) {
    throw DatasetError(e.what());
  }
}

void checkImageSize(const cv::Mat& image, const std::string& image_path, const camera::CameraCalibration& calib,
                    const std::string& calib_path) {
  if (image.cols == calib.camera.width() && image.rows == calib.camera.height()) return;
  throw DatasetError("image '" + image_path + "' is " + std::to_string(image.cols) + "x" + std::to_string(image.rows) +
                     " but the calibration '" + calib_path + "' is for " + std::to_string(calib.camera.width()) + "x" +
                     std::to_string(calib.camera.height()));
}

std::string trim(const std::string& s) {
  const char* ws = " \t\r\n";
  const std::size_t b = s.find_first_not_of(ws);
  if (b == std::string::npos) return {};
  return s.substr(b, s.find_last_not_of(ws) - b + 1);
}

bool parseDouble(const std::string& text, double* value) {
  if (text.empty()) return false;
  errno = 0;
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (errno != 0 || end != text.c_str() + text.size() || !std::isfinite(v)) return false;
  *value = v;
  return true;
}

fs::path findEurocCamFolder(const fs::path& path) {
  std::error_code ec;
  auto looks_like_cam = [&](const fs::path& c) {
    return fs::is_regular_file(c / "data.csv", ec) || fs::is_directory(c / "data", ec) ||
           fs::is_regular_file(c / "sensor.yaml", ec);
  };
  if (looks_like_cam(path / "mav0" / "cam0")) return path / "mav0" / "cam0";
  if (fs::is_directory(path / "cam0", ec) && looks_like_cam(path / "cam0")) return path / "cam0";
  // The cam0 folder itself: data.csv, or data/ with sensor.yaml.
  if (fs::is_regular_file(path / "data.csv", ec) ||
      (fs::is_directory(path / "data", ec) && fs::is_regular_file(path / "sensor.yaml", ec))) {
    return path;
  }
  if (fs::is_directory(path / "mav0", ec)) return path / "mav0" / "cam0";  // reported as missing by openEuroc
  if (fs::is_directory(path / "cam0", ec)) return path / "cam0";
  return {};
}

}  // namespace detail

std::string detectDatasetKind(const std::string& path_text) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path path(path_text);
  if (fs::is_regular_file(path, ec)) return path.extension() == ".bag" ? "rosbag" : "";
  if (!fs::is_directory(path, ec)) return "";
  if (!detail::findEurocCamFolder(path).empty()) return "euroc";
  if (fs::is_regular_file(path / "rgb.txt", ec)) return "tum";
  if (fs::is_directory(path / "image_0", ec) || fs::is_directory(path / "image_l", ec)) return "kitti";
  return "";
}

std::unique_ptr<Dataset> openDataset(const std::string& path_text, const DatasetOptions& options) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path path(path_text);
  if (!fs::exists(path, ec)) throw DatasetError("dataset '" + path_text + "' does not exist");
  const std::string kind = detectDatasetKind(path_text);
  if (kind == "rosbag") {
    throw DatasetError("'" + path_text + "' is a rosbag: open it with the ROS layer (vitamin_e/ros/bag_dataset.h)");
  }
  if (!fs::is_directory(path, ec)) {
    throw DatasetError("dataset '" + path_text + "' is not a folder (nor a .bag file)");
  }
  if (!options.calibration_path.empty() && !fs::is_regular_file(options.calibration_path, ec)) {
    throw DatasetError("calibration file '" + options.calibration_path + "' does not exist");
  }
  if (kind == "euroc") return detail::openEuroc(path, options);
  if (kind == "tum") return detail::openTum(path, options);
  if (kind == "kitti") return detail::openKitti(path, options);
  throw DatasetError("'" + path_text +
                     "' is not a known dataset layout (expected EuRoC mav0/cam0/data.csv, TUM rgb.txt, "
                     "or KITTI image_0/ + calib.txt)");
}

}  // namespace vitamin_e::io
