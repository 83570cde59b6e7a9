// EuRoC ASL, TUM RGB-D and KITTI odometry folder readers.
#include <algorithm>
#include <cctype>
#include <cstdio>
#include <fstream>

#include "folder_dataset.h"

namespace vitamin_e::io::detail {

namespace {

std::vector<std::string> readLines(const fs::path& file) {
  std::ifstream in(file);
  if (!in) throw DatasetError("cannot open '" + file.string() + "'");
  std::vector<std::string> lines;
  std::string line;
  while (std::getline(in, line)) lines.push_back(line);
  return lines;
}

bool allDigits(const std::string& s) {
  return !s.empty() && std::all_of(s.begin(), s.end(), [](unsigned char c) { return std::isdigit(c); });
}

[[noreturn]] void badLine(const fs::path& file, std::size_t line_no, const std::string& expected) {
  throw DatasetError("'" + file.string() + "' line " + std::to_string(line_no) + ": expected " + expected);
}

void checkIncreasing(const std::vector<FrameFile>& frames, const fs::path& file) {
  for (std::size_t i = 1; i < frames.size(); ++i) {
    if (!(frames[i].t > frames[i - 1].t)) {
      throw DatasetError("'" + file.string() + "': timestamps do not increase (" + frames[i - 1].t_text + " then " +
                         frames[i].t_text + ")");
    }
  }
}

std::string firstExisting(const std::vector<fs::path>& candidates) {
  std::error_code ec;
  for (const fs::path& p : candidates) {
    if (fs::is_regular_file(p, ec)) return p.string();
  }
  return {};
}

}  // namespace

std::unique_ptr<Dataset> openEuroc(const fs::path& path, const DatasetOptions& options) {
  std::error_code ec;
  const fs::path cam = findEurocCamFolder(path);
  if (!fs::is_directory(cam, ec))
    throw DatasetError("EuRoC folder '" + path.string() + "' has no '" + cam.string() + "'");
  const fs::path csv = cam / "data.csv";
  if (!fs::is_regular_file(csv, ec)) throw DatasetError("EuRoC folder '" + cam.string() + "' has no data.csv");
  const fs::path images = cam / "data";
  if (!fs::is_directory(images, ec)) {
    throw DatasetError("EuRoC folder '" + cam.string() + "' has no images folder 'data/'");
  }
  std::vector<FrameFile> frames;
  const std::vector<std::string> lines = readLines(csv);
  for (std::size_t n = 0; n < lines.size(); ++n) {
    const std::string line = trim(lines[n]);
    if (line.empty() || line[0] == '#') continue;
    const std::size_t comma = line.find(',');
    if (comma == std::string::npos) badLine(csv, n + 1, "'timestamp_ns,filename'");
    const std::string ns = trim(line.substr(0, comma));
    const std::string name = trim(line.substr(comma + 1));
    if (!allDigits(ns) || ns.size() > 19 || name.empty() || name.find(',') != std::string::npos) {
      badLine(csv, n + 1, "'timestamp_ns,filename', got '" + line + "'");
    }
    FrameFile f;
    f.t_text = nanosecondsToSecondsText(ns);
    const std::size_t split = ns.size() > 9 ? ns.size() - 9 : 0;
    const double sec = split ? static_cast<double>(std::stoull(ns.substr(0, split))) : 0.0;
    f.t = sec + static_cast<double>(std::stoull(ns.substr(split))) * 1e-9;
    f.path = (images / name).string();
    frames.push_back(std::move(f));
  }
  if (frames.empty()) throw DatasetError("'" + csv.string() + "' lists no images");
  checkIncreasing(frames, csv);

  const cv::Mat first = readGray(frames.front().path);
  camera::CameraCalibration calib;
  std::string calib_path = options.calibration_path;
  if (calib_path.empty()) {
    calib_path = (cam / "sensor.yaml").string();
    if (!fs::is_regular_file(calib_path, ec)) {
      throw DatasetError("EuRoC folder '" + cam.string() + "' has no sensor.yaml (pass a calibration file)");
    }
  }
  if (options.calibration_path.empty()) {
    try {
      calib = camera::loadEurocSensorYaml(calib_path);
    } catch (const camera::CalibrationError& e) {
      throw DatasetError(e.what());
    }
  } else {
    calib = loadCalibrationFor(calib_path, first.cols, first.rows);
  }
  checkImageSize(first, frames.front().path, calib, calib_path);

  // The folder holding mav0/ (a render's groundtruth_cam0_tum.txt is the camera trajectory: preferred).
  const fs::path mav0 = cam.parent_path();
  const std::string gt =
      firstExisting({mav0.parent_path() / "groundtruth_cam0_tum.txt", mav0 / "groundtruth_cam0_tum.txt",
                     mav0 / "state_groundtruth_estimate0" / "data.csv"});
  return std::make_unique<FolderDataset>("euroc", std::move(frames), std::move(calib), gt);
}

std::unique_ptr<Dataset> openTum(const fs::path& path, const DatasetOptions& options) {
  std::error_code ec;
  const fs::path list = path / "rgb.txt";
  std::vector<FrameFile> frames;
  const std::vector<std::string> lines = readLines(list);
  for (std::size_t n = 0; n < lines.size(); ++n) {
    const std::string line = trim(lines[n]);
    if (line.empty() || line[0] == '#') continue;
    const std::size_t sp = line.find_first_of(" \t");
    if (sp == std::string::npos) badLine(list, n + 1, "'timestamp path'");
    FrameFile f;
    f.t_text = line.substr(0, sp);
    const std::string rel = trim(line.substr(sp + 1));
    if (!parseDouble(f.t_text, &f.t) || rel.empty()) badLine(list, n + 1, "'timestamp path', got '" + line + "'");
    f.path = (path / rel).string();
    frames.push_back(std::move(f));
  }
  if (frames.empty()) throw DatasetError("'" + list.string() + "' lists no images");
  checkIncreasing(frames, list);

  std::string calib_path = options.calibration_path;
  if (calib_path.empty()) calib_path = firstExisting({path / "camera.yaml", path / "calibration.yaml"});
  if (calib_path.empty()) {
    throw DatasetError("TUM folder '" + path.string() +
                       "' has no camera.yaml or calibration.yaml: pass a calibration file (--calib)");
  }
  const cv::Mat first = readGray(frames.front().path);
  camera::CameraCalibration calib = loadCalibrationFor(calib_path, first.cols, first.rows);
  checkImageSize(first, frames.front().path, calib, calib_path);
  const std::string gt = firstExisting({path / "groundtruth.txt"});
  return std::make_unique<FolderDataset>("tum", std::move(frames), std::move(calib), gt);
}

std::unique_ptr<Dataset> openKitti(const fs::path& path, const DatasetOptions& options) {
  std::error_code ec;
  const fs::path images = fs::is_directory(path / "image_0", ec) ? path / "image_0" : path / "image_l";
  std::vector<std::string> files;
  for (const auto& entry : fs::directory_iterator(images, ec)) {
    const std::string ext = entry.path().extension().string();
    if (entry.is_regular_file(ec) && (ext == ".png" || ext == ".jpg" || ext == ".pgm")) {
      files.push_back(entry.path().string());
    }
  }
  if (ec) throw DatasetError("cannot list '" + images.string() + "': " + ec.message());
  if (files.empty()) throw DatasetError("KITTI folder '" + images.string() + "' holds no images");
  std::sort(files.begin(), files.end());

  std::vector<FrameFile> frames(files.size());
  const fs::path times = path / "times.txt";
  if (fs::is_regular_file(times, ec)) {
    std::size_t k = 0;
    const std::vector<std::string> lines = readLines(times);
    for (std::size_t n = 0; n < lines.size(); ++n) {
      const std::string line = trim(lines[n]);
      if (line.empty()) continue;
      if (k >= frames.size()) break;  // times.txt of the full sequence beside a subset of images
      if (!parseDouble(line, &frames[k].t)) badLine(times, n + 1, "a time in seconds, got '" + line + "'");
      frames[k++].t_text = line;
    }
    if (k < frames.size()) {
      throw DatasetError("'" + times.string() + "' has " + std::to_string(k) + " times for " +
                         std::to_string(frames.size()) + " images");
    }
  } else {
    for (std::size_t i = 0; i < frames.size(); ++i) {
      frames[i].t = 0.1 * static_cast<double>(i);
      char buf[32];
      std::snprintf(buf, sizeof(buf), "%.6f", frames[i].t);
      frames[i].t_text = buf;
    }
  }
  for (std::size_t i = 0; i < frames.size(); ++i) frames[i].path = files[i];
  checkIncreasing(frames, fs::is_regular_file(times, ec) ? times : images);

  std::string calib_path = options.calibration_path;
  if (calib_path.empty()) calib_path = firstExisting({path / "calib.txt"});
  if (calib_path.empty()) throw DatasetError("KITTI folder '" + path.string() + "' has no calib.txt");
  const cv::Mat first = readGray(frames.front().path);
  camera::CameraCalibration calib = loadCalibrationFor(calib_path, first.cols, first.rows);
  checkImageSize(first, frames.front().path, calib, calib_path);
  const std::string gt = firstExisting({path / "poses.txt"});
  return std::make_unique<FolderDataset>("kitti", std::move(frames), std::move(calib), gt);
}

}  // namespace vitamin_e::io::detail
