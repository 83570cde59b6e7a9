// Decoding a folder of PNG frames: cv::imread (libpng + zlib) against io::decodeGrayPng
// (libdeflate), each image read into memory first so that only the decoding is timed. Checks
// that both give the same pixels. Median thread CPU ms per image over the images and repeats.
//   bench_io_png_decode FOLDER [--images N] [--repeats R]
// FOLDER: PNG files (e.g. a EuRoC mav0/cam0/data or a KITTI image_0 folder).
// Last line of the output: JSON summary.
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "cli.h"
#include "vitamin_e/common/timing.h"
#include "vitamin_e/io/png_gray.h"

namespace {

const char* const kUsage = "usage: bench_io_png_decode FOLDER [--images N] [--repeats R]\n"
                           "  FOLDER        a folder of PNG frames (EuRoC mav0/cam0/data, KITTI image_0)\n"
                           "  --images N    the first N PNG files by name (default 100)\n"
                           "  --repeats R   passes over them (default 3)\n";

std::vector<std::uint8_t> readBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

}  // namespace

int main(int argc, char** argv) {
  namespace cli = vitamin_e::cli;
  namespace fs = std::filesystem;
  std::string folder;
  int images = 100, repeats = 3;
  cli::ArgParser args(argc, argv, kUsage);
  while (args.more()) {
    if (args.positional(&folder) || args.value("--images", &images) || args.value("--repeats", &repeats)) continue;
    args.unknown();
  }
  if (folder.empty()) cli::fail("FOLDER is missing (see --help)");
  if (images < 1) cli::fail("--images must be >= 1");
  if (repeats < 1) cli::fail("--repeats must be >= 1");
  std::error_code ec;
  if (!fs::is_directory(folder, ec)) cli::fail("'" + folder + "' is not a folder");
  std::vector<std::string> paths;
  for (const auto& e : fs::directory_iterator(folder, ec)) {
    if (e.path().extension() == ".png") paths.push_back(e.path().string());
  }
  if (paths.empty()) cli::fail("no .png file in '" + folder + "'");
  std::sort(paths.begin(), paths.end());
  paths.resize(std::min(paths.size(), static_cast<std::size_t>(images)));

  std::vector<std::vector<std::uint8_t>> files;
  files.reserve(paths.size());
  for (const std::string& p : paths) files.push_back(readBytes(p));
  std::vector<double> opencv_ms, ours_ms;
  int refused = 0, differ = 0;
  for (int r = 0; r < repeats; ++r) {
    for (const auto& bytes : files) {
      double c0 = vitamin_e::threadCpuMs();
      const cv::Mat reference = cv::imdecode(bytes, cv::IMREAD_UNCHANGED);
      opencv_ms.push_back(vitamin_e::threadCpuMs() - c0);
      cv::Mat ours;
      c0 = vitamin_e::threadCpuMs();
      const bool ok = vitamin_e::io::decodeGrayPng(bytes.data(), bytes.size(), &ours);
      ours_ms.push_back(vitamin_e::threadCpuMs() - c0);
      if (r > 0) continue;
      if (!ok) {
        ++refused;
      } else if (reference.size() != ours.size() || reference.type() != ours.type() ||
                 cv::countNonZero(reference != ours) != 0) {
        ++differ;
      }
    }
  }
  const double opencv_med = vitamin_e::percentile(opencv_ms, 50.0), ours_med = vitamin_e::percentile(ours_ms, 50.0);
  std::printf("%zu PNG files of %s, %d passes: cv::imread's decoder %.2f ms, decodeGrayPng %.2f ms per image "
              "(median thread CPU); %d left to OpenCV (not 8-bit grey), %d with other pixels\n",
              files.size(), folder.c_str(), repeats, opencv_med, ours_med, refused, differ);
  std::printf("{\"images\":%zu,\"repeats\":%d,\"opencv_ms_median\":%.3f,\"decode_gray_png_ms_median\":%.3f,"
              "\"refused\":%d,\"differ\":%d}\n",
              files.size(), repeats, opencv_med, ours_med, refused, differ);
  return differ == 0 ? 0 : 1;
}
