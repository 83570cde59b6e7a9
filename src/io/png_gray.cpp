#include "vitamin_e/io/png_gray.h"

#include <cstdlib>
#include <cstring>
#include <memory>
#include <vector>

#include <libdeflate.h>

namespace vitamin_e::io {

namespace {

constexpr std::uint8_t kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
// cv::imread refuses larger images (CV_IO_MAX_IMAGE_PIXELS); such a file goes to it.
constexpr std::uint64_t kMaxPixels = std::uint64_t{1} << 30;
// Deflate's largest expansion (a 258-byte match in about two bits), rounded up.
constexpr std::size_t kMaxDeflateRatio = 1040;

std::uint32_t readBigEndian32(const std::uint8_t* p) {
  return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) | std::uint32_t{p[3]};
}

bool isChunk(const std::uint8_t* type, const char* name) { return std::memcmp(type, name, 4) == 0; }

// Ancillary chunks that leave the pixels of an 8-bit grey image as they are (text, time, pixel
// size). gAMA, sBIT, tRNS, iCCP and the like may change what a decoder returns: not taken here.
bool isMetadata(const std::uint8_t* type) {
  return isChunk(type, "tEXt") || isChunk(type, "zTXt") || isChunk(type, "iTXt") || isChunk(type, "tIME") ||
         isChunk(type, "pHYs");
}

struct DecompressorDeleter {
  void operator()(libdeflate_decompressor* d) const { libdeflate_free_decompressor(d); }
};

// Undoes one row's filter (PNG specification, section 9; one byte per pixel). `up` is the
// previous decoded row, zeros for the first row.
bool unfilterRow(int filter, const std::uint8_t* in, const std::uint8_t* up, std::uint8_t* out, int width) {
  switch (filter) {
    case 0: std::memcpy(out, in, static_cast<std::size_t>(width)); return true;
    case 1: {  // Sub
      int left = 0;
      for (int x = 0; x < width; ++x) out[x] = static_cast<std::uint8_t>(left = (in[x] + left) & 0xff);
      return true;
    }
    case 2:  // Up
      for (int x = 0; x < width; ++x) out[x] = static_cast<std::uint8_t>(in[x] + up[x]);
      return true;
    case 3: {  // Average
      int left = 0;
      for (int x = 0; x < width; ++x) out[x] = static_cast<std::uint8_t>(left = (in[x] + ((left + up[x]) >> 1)) & 0xff);
      return true;
    }
    case 4: {  // Paeth: the neighbour (left a, up b, up-left c) nearest to a + b - c, ties in that order
      int left = 0;
      int up_left = 0;
      for (int x = 0; x < width; ++x) {
        const int above = up[x];
        const int to_left = std::abs(above - up_left);                // |p - a|
        const int to_above = std::abs(left - up_left);                // |p - b|
        const int to_up_left = std::abs(left + above - 2 * up_left);  // |p - c|
        int predictor = up_left;
        if (to_left <= to_above && to_left <= to_up_left) {
          predictor = left;
        } else if (to_above <= to_up_left) {
          predictor = above;
        }
        left = (in[x] + predictor) & 0xff;
        out[x] = static_cast<std::uint8_t>(left);
        up_left = above;
      }
      return true;
    }
    default: return false;
  }
}

}  // namespace

bool hasPngSignature(const std::uint8_t* bytes, std::size_t size) {
  return size >= sizeof(kSignature) && std::memcmp(bytes, kSignature, sizeof(kSignature)) == 0;
}

bool decodeGrayPng(const std::uint8_t* bytes, std::size_t size, cv::Mat* gray) {
  if (!hasPngSignature(bytes, size)) return false;
  std::size_t pos = sizeof(kSignature);
  std::uint32_t width = 0;
  std::uint32_t height = 0;
  bool have_header = false;
  bool idat_ended = false;
  bool have_end = false;
  std::vector<std::uint8_t> compressed;
  while (size - pos >= 12) {
    const std::uint32_t length = readBigEndian32(bytes + pos);
    if (length > size - pos - 12) return false;  // truncated
    const std::uint8_t* type = bytes + pos + 4;
    const std::uint8_t* body = type + 4;
    if (libdeflate_crc32(0, type, std::size_t{length} + 4) != readBigEndian32(body + length)) return false;
    if (!have_header) {
      if (!isChunk(type, "IHDR") || length != 13) return false;
      width = readBigEndian32(body);
      height = readBigEndian32(body + 4);
      // bit depth 8, colour type 0 (grey), compression 0, filter method 0, no interlace
      if (body[8] != 8 || body[9] != 0 || body[10] != 0 || body[11] != 0 || body[12] != 0) return false;
      if (width == 0 || height == 0 || width > 0x7fffffffU || height > 0x7fffffffU ||
          std::uint64_t{width} * height > kMaxPixels) {
        return false;
      }
      have_header = true;
    } else if (isChunk(type, "IDAT")) {
      if (idat_ended) return false;  // the data must be consecutive
      compressed.insert(compressed.end(), body, body + length);
    } else if (isChunk(type, "IEND")) {
      have_end = true;
      break;
    } else if (isMetadata(type)) {
      idat_ended = !compressed.empty();
    } else {
      return false;
    }
    pos += std::size_t{length} + 12;
  }
  if (!have_end || compressed.empty()) return false;

  const int cols = static_cast<int>(width);
  const int rows = static_cast<int>(height);
  const std::size_t stride = std::size_t{width} + 1;  // a filter byte, then the row
  // Deflate expands by at most about 1032:1: a header that claims more rows than the data can hold
  // is damaged, and refused before its buffer is allocated.
  if (stride * height > compressed.size() * kMaxDeflateRatio) return false;
  std::vector<std::uint8_t> filtered(stride * height);
  const std::unique_ptr<libdeflate_decompressor, DecompressorDeleter> inflater(libdeflate_alloc_decompressor());
  if (!inflater) return false;
  std::size_t inflated = 0;
  if (libdeflate_zlib_decompress(inflater.get(), compressed.data(), compressed.size(), filtered.data(), filtered.size(),
                                 &inflated) != LIBDEFLATE_SUCCESS ||
      inflated != filtered.size()) {
    return false;
  }
  cv::Mat out(rows, cols, CV_8UC1);
  const std::vector<std::uint8_t> zeros(width, 0);
  for (int y = 0; y < rows; ++y) {
    const std::uint8_t* in = filtered.data() + stride * static_cast<std::size_t>(y);
    const std::uint8_t* up = y == 0 ? zeros.data() : out.ptr<std::uint8_t>(y - 1);
    if (!unfilterRow(in[0], in + 1, up, out.ptr<std::uint8_t>(y), cols)) return false;
  }
  *gray = out;
  return true;
}

}  // namespace vitamin_e::io
