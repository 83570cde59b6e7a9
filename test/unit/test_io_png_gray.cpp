// The fast PNG decoder (io/png_gray.h) against OpenCV's: the same pixels for every row filter and
// every way OpenCV writes a grey PNG, and a refusal (so that OpenCV decides) for every other PNG
// and for damaged files.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <libdeflate.h>
#include <opencv2/imgcodecs.hpp>

#include "vitamin_e/io/png_gray.h"

namespace {

using Bytes = std::vector<std::uint8_t>;

cv::Mat texture(int rows, int cols, unsigned seed) {
  // Smooth gradients and noise: every filter has something to predict.
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> noise(-6, 6);
  cv::Mat img(rows, cols, CV_8UC1);
  for (int y = 0; y < rows; ++y) {
    for (int x = 0; x < cols; ++x) {
      const int v = 128 + static_cast<int>(90.0 * std::sin(0.07 * x + 0.11 * y)) + noise(rng);
      img.at<std::uint8_t>(y, x) = static_cast<std::uint8_t>(std::min(255, std::max(0, v)));
    }
  }
  return img;
}

void putBigEndian32(Bytes* out, std::uint32_t v) {
  for (int shift = 24; shift >= 0; shift -= 8) out->push_back(static_cast<std::uint8_t>(v >> shift));
}

void putChunk(Bytes* out, const char* type, const Bytes& body) {
  putBigEndian32(out, static_cast<std::uint32_t>(body.size()));
  Bytes typed(type, type + 4);
  typed.insert(typed.end(), body.begin(), body.end());
  out->insert(out->end(), typed.begin(), typed.end());
  putBigEndian32(out, libdeflate_crc32(0, typed.data(), typed.size()));
}

int paeth(int a, int b, int c) {
  const int p = a + b - c;
  const int pa = std::abs(p - a), pb = std::abs(p - b), pc = std::abs(p - c);
  if (pa <= pb && pa <= pc) return a;
  return pb <= pc ? b : c;
}

struct PngOptions {
  int idat_chunks = 1;
  bool text_before_data = false;
  std::uint8_t bit_depth = 8, colour_type = 0, interlace = 0;
  const char* extra_chunk = nullptr;  // an ancillary chunk inserted before the data
};

// A grey PNG written by hand: row y uses filter filters[y % size] (0 None .. 4 Paeth).
Bytes makePng(const cv::Mat& img, const std::vector<int>& filters, const PngOptions& o = {}) {
  Bytes raw;
  for (int y = 0; y < img.rows; ++y) {
    const int f = filters[static_cast<std::size_t>(y) % filters.size()];
    raw.push_back(static_cast<std::uint8_t>(f));
    for (int x = 0; x < img.cols; ++x) {
      const int v = img.at<std::uint8_t>(y, x);
      const int a = x > 0 ? img.at<std::uint8_t>(y, x - 1) : 0;
      const int b = y > 0 ? img.at<std::uint8_t>(y - 1, x) : 0;
      const int c = x > 0 && y > 0 ? img.at<std::uint8_t>(y - 1, x - 1) : 0;
      const int predictor = f == 0 ? 0 : f == 1 ? a : f == 2 ? b : f == 3 ? (a + b) / 2 : paeth(a, b, c);
      raw.push_back(static_cast<std::uint8_t>((v - predictor) & 0xff));
    }
  }
  libdeflate_compressor* zip = libdeflate_alloc_compressor(6);
  Bytes z(libdeflate_zlib_compress_bound(zip, raw.size()));
  z.resize(libdeflate_zlib_compress(zip, raw.data(), raw.size(), z.data(), z.size()));
  libdeflate_free_compressor(zip);

  Bytes png = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  Bytes header;
  putBigEndian32(&header, static_cast<std::uint32_t>(img.cols));
  putBigEndian32(&header, static_cast<std::uint32_t>(img.rows));
  header.insert(header.end(), {o.bit_depth, o.colour_type, 0, 0, o.interlace});
  putChunk(&png, "IHDR", header);
  if (o.text_before_data) putChunk(&png, "tEXt", Bytes{'k', 0, 'v'});
  if (o.extra_chunk) putChunk(&png, o.extra_chunk, Bytes{0, 1});
  const std::size_t part =
      (z.size() + static_cast<std::size_t>(o.idat_chunks) - 1) / static_cast<std::size_t>(o.idat_chunks);
  for (std::size_t begin = 0; begin < z.size(); begin += part) {
    putChunk(&png, "IDAT",
             Bytes(z.begin() + static_cast<std::ptrdiff_t>(begin),
                   z.begin() + static_cast<std::ptrdiff_t>(std::min(z.size(), begin + part))));
  }
  putChunk(&png, "IEND", {});
  return png;
}

cv::Mat opencvDecode(const Bytes& png) { return cv::imdecode(png, cv::IMREAD_UNCHANGED); }

bool same(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && cv::countNonZero(a != b) == 0;
}

TEST(PngGray, EveryRowFilterDecodesToThePixelsOpenCvGives) {
  for (const cv::Size size : {cv::Size(1, 1), cv::Size(37, 23), cv::Size(640, 48)}) {
    const cv::Mat img = texture(size.height, size.width, 7);
    for (const std::vector<int>& filters : {std::vector<int>{0}, {1}, {2}, {3}, {4}, {4, 3, 2, 1, 0}}) {
      const Bytes png = makePng(img, filters);
      cv::Mat ours;
      ASSERT_TRUE(vitamin_e::io::decodeGrayPng(png.data(), png.size(), &ours)) << size << " filter " << filters[0];
      EXPECT_TRUE(same(ours, img)) << size << " filter " << filters[0];
      EXPECT_TRUE(same(ours, opencvDecode(png))) << size << " filter " << filters[0];
    }
  }
}

TEST(PngGray, SplitDataAndTextChunksAreRead) {
  const cv::Mat img = texture(31, 45, 3);
  PngOptions o;
  o.idat_chunks = 4;
  o.text_before_data = true;
  const Bytes png = makePng(img, {4, 1, 2}, o);
  cv::Mat ours;
  ASSERT_TRUE(vitamin_e::io::decodeGrayPng(png.data(), png.size(), &ours));
  EXPECT_TRUE(same(ours, img));
}

TEST(PngGray, WhatOpenCvWritesDecodesTheSame) {
  const cv::Mat img = texture(120, 161, 11);
  for (int level : {0, 1, 3, 9}) {
    for (int strategy :
         {cv::IMWRITE_PNG_STRATEGY_DEFAULT, cv::IMWRITE_PNG_STRATEGY_FILTERED, cv::IMWRITE_PNG_STRATEGY_HUFFMAN_ONLY,
          cv::IMWRITE_PNG_STRATEGY_RLE, cv::IMWRITE_PNG_STRATEGY_FIXED}) {
      std::vector<std::uint8_t> png;
      ASSERT_TRUE(
          cv::imencode(".png", img, png, {cv::IMWRITE_PNG_COMPRESSION, level, cv::IMWRITE_PNG_STRATEGY, strategy}));
      cv::Mat ours;
      ASSERT_TRUE(vitamin_e::io::decodeGrayPng(png.data(), png.size(), &ours)) << level << " " << strategy;
      EXPECT_TRUE(same(ours, img)) << level << " " << strategy;
    }
  }
}

TEST(PngGray, OtherPngsAreLeftToOpenCv) {
  const cv::Mat grey = texture(20, 30, 5);
  cv::Mat colour;
  cv::merge(std::vector<cv::Mat>{grey, grey, grey}, colour);
  cv::Mat deep;
  grey.convertTo(deep, CV_16U, 256.0);
  for (const cv::Mat& m : {colour, deep}) {
    std::vector<std::uint8_t> png;
    ASSERT_TRUE(cv::imencode(".png", m, png));
    cv::Mat out;
    EXPECT_FALSE(vitamin_e::io::decodeGrayPng(png.data(), png.size(), &out));
    EXPECT_TRUE(out.empty());  // untouched
  }
  PngOptions interlaced;
  interlaced.interlace = 1;
  PngOptions transparent;
  transparent.extra_chunk = "tRNS";
  PngOptions gamma;
  gamma.extra_chunk = "gAMA";
  for (const PngOptions& o : {interlaced, transparent, gamma}) {
    const Bytes png = makePng(grey, {0}, o);
    cv::Mat out;
    EXPECT_FALSE(vitamin_e::io::decodeGrayPng(png.data(), png.size(), &out));
  }
  const Bytes jpeg_like = {0xff, 0xd8, 0xff, 0xe0, 0, 0x10, 'J', 'F', 'I', 'F'};
  cv::Mat out;
  EXPECT_FALSE(vitamin_e::io::hasPngSignature(jpeg_like.data(), jpeg_like.size()));
  EXPECT_FALSE(vitamin_e::io::decodeGrayPng(jpeg_like.data(), jpeg_like.size(), &out));
}

TEST(PngGray, DamagedFilesAreRefused) {
  const cv::Mat img = texture(16, 24, 9);
  const Bytes good = makePng(img, {4});
  cv::Mat out;
  ASSERT_TRUE(vitamin_e::io::decodeGrayPng(good.data(), good.size(), &out));

  Bytes bad_crc = good;
  bad_crc[8 + 8 + 13] ^= 0x01;  // IHDR's CRC
  Bytes flipped_data = good;
  flipped_data[8 + 25 + 8 + 3] ^= 0x40;  // inside the first IDAT: its CRC no longer matches
  const Bytes truncated(good.begin(), good.end() - 20);
  const Bytes no_end(good.begin(), good.end() - 12);
  // A filter byte of 5 (no such filter), with valid checksums.
  Bytes raw_rows;
  for (int y = 0; y < img.rows; ++y) {
    raw_rows.push_back(y == 3 ? 5 : 0);
    raw_rows.insert(raw_rows.end(), img.ptr<std::uint8_t>(y), img.ptr<std::uint8_t>(y) + img.cols);
  }
  libdeflate_compressor* zip = libdeflate_alloc_compressor(1);
  Bytes z(libdeflate_zlib_compress_bound(zip, raw_rows.size()));
  z.resize(libdeflate_zlib_compress(zip, raw_rows.data(), raw_rows.size(), z.data(), z.size()));
  libdeflate_free_compressor(zip);
  Bytes bad_filter(good.begin(), good.begin() + 8 + 25);
  putChunk(&bad_filter, "IDAT", z);
  putChunk(&bad_filter, "IEND", {});
  // Data for one row fewer than the header says.
  const Bytes short_data = makePng(img.rowRange(0, img.rows - 1), {0});
  Bytes too_tall(good.begin(), good.begin() + 8);
  Bytes header;
  putBigEndian32(&header, static_cast<std::uint32_t>(img.cols));
  putBigEndian32(&header, static_cast<std::uint32_t>(img.rows));
  header.insert(header.end(), {8, 0, 0, 0, 0});
  putChunk(&too_tall, "IHDR", header);
  too_tall.insert(too_tall.end(), short_data.begin() + 8 + 25, short_data.end());

  // A header that claims far more pixels than the data can hold (the data of 1x1).
  Bytes huge(good.begin(), good.begin() + 8);
  Bytes huge_header;
  putBigEndian32(&huge_header, 20000);
  putBigEndian32(&huge_header, 20000);
  huge_header.insert(huge_header.end(), {8, 0, 0, 0, 0});
  putChunk(&huge, "IHDR", huge_header);
  const Bytes one_pixel = makePng(img.rowRange(0, 1).colRange(0, 1), {0});
  huge.insert(huge.end(), one_pixel.begin() + 8 + 25, one_pixel.end());

  const std::vector<std::pair<const char*, const Bytes*>> damaged = {
      {"bad CRC", &bad_crc},     {"flipped data", &flipped_data}, {"truncated", &truncated}, {"no IEND", &no_end},
      {"filter 5", &bad_filter}, {"too little data", &too_tall},  {"huge header", &huge}};
  for (const auto& [name, png] : damaged) {
    cv::Mat refused;
    EXPECT_FALSE(vitamin_e::io::decodeGrayPng(png->data(), png->size(), &refused)) << name;
    EXPECT_TRUE(refused.empty()) << name;
  }
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
