#pragma once
// The images SLAM datasets store (EuRoC, KITTI, the project's renders) are 8-bit greyscale,
// non-interlaced PNG. libpng + zlib behind cv::imread decode a KITTI frame in about 4 ms; this
// decoder inflates with libdeflate and undoes the row filters itself, with the same pixels, in
// about 1.5 ms (docs/PERFORMANCE.md, "Image decoding"). It takes only that one kind of PNG and
// only well-formed files: anything else makes it return false, and the caller decodes the file
// with OpenCV, which gives its own pixels or its own error.
#include <cstddef>
#include <cstdint>

#include <opencv2/core.hpp>

namespace vitamin_e::io {

// True if `bytes` is a PNG starting with the PNG signature; cheap, for choosing the decoder.
bool hasPngSignature(const std::uint8_t* bytes, std::size_t size);

// Decodes an 8-bit greyscale non-interlaced PNG into *gray (CV_8UC1). Returns false, leaving
// *gray untouched, for every other PNG (colour, palette, 16 bit, interlaced, transparency or
// colour-space chunks) and for a damaged one (bad CRC or zlib checksum, truncated, wrong size).
bool decodeGrayPng(const std::uint8_t* bytes, std::size_t size, cv::Mat* gray);

}  // namespace vitamin_e::io
