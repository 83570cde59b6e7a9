#pragma once
// Versioned binary files with a readable first line (the map file, the TSDF
// file): "<text>\n" + 8-byte payload size + 8-byte FNV-1a checksum + payload.
// The payload is built with BinaryWriter (fixed-width little-endian values,
// the host order on every platform this builds on) and read back with
// BinaryReader, which checks every read against the end of the data and every
// count against the bytes left, so a damaged file gives a BinaryFileError naming
// what is wrong, never a crash or a huge allocation. Files are written
// atomically: a temporary file in the same folder, flushed, then renamed over
// the target, so a reader never sees half a file and a failed write leaves the
// old one in place.
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace vitamin_e {

struct BinaryFileError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

std::uint64_t fnv1a64(const char* data, std::size_t size);

class BinaryWriter {
 public:
  template <typename T>
  void put(const T& value) {
    static_assert(std::is_arithmetic<T>::value, "put() takes numbers");
    const std::size_t n = bytes_.size();
    bytes_.resize(n + sizeof(T));
    std::memcpy(&bytes_[n], &value, sizeof(T));
  }
  void putString(const std::string& s) {
    put(static_cast<std::uint32_t>(s.size()));
    bytes_.append(s);
  }
  void putDoubles(const double* v, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) put(v[i]);
  }
  const std::string& bytes() const { return bytes_; }
  std::string& bytes() { return bytes_; }

 private:
  std::string bytes_;
};

// Reads a payload; every failure throws BinaryFileError("<what>: ...").
class BinaryReader {
 public:
  BinaryReader(const char* data, std::size_t size, std::string what)
      : p_(data), end_(data + size), what_(std::move(what)) {}
  template <typename T>
  T get() {
    static_assert(std::is_arithmetic<T>::value, "get() returns numbers");
    need(sizeof(T));
    T v;
    std::memcpy(&v, p_, sizeof(T));
    p_ += sizeof(T);
    return v;
  }
  double getFinite(const char* field) {
    const double v = get<double>();
    if (!(v == v) || v > 1e300 || v < -1e300) fail(std::string("non-finite ") + field);
    return v;
  }
  std::string getString(std::size_t max_size);
  // A count of items each at least min_item_bytes long: refused when the rest
  // of the payload cannot hold them (a damaged count, not an allocation).
  std::uint64_t getCount(std::size_t min_item_bytes, const char* items);
  std::size_t remaining() const { return static_cast<std::size_t>(end_ - p_); }
  [[noreturn]] void fail(const std::string& message) const;

 private:
  void need(std::size_t n) const {
    if (remaining() < n) fail("unexpected end of the data");
  }
  const char* p_;
  const char* end_;
  std::string what_;
};

// Writes "<header_line>\n" + sizes + payload to path atomically. False (and
// *error) when it cannot; the target is then untouched.
bool writeBinaryFile(const std::string& path, const std::string& header_line, const std::string& payload,
                     std::string* error);

struct BinaryFileContents {
  std::string header_line;  // without the newline
  std::string payload;      // checked against its size and checksum
  int version = 0;          // the format version of the header line
};

// Reads a file written by writeBinaryFile whose header line starts with
// `magic` (e.g. "vitamin_e map v") followed by the format version and a comma.
// Throws BinaryFileError naming the file and the problem: missing, empty, not
// such a file (foreign), damaged header, another format version, truncated,
// corrupt. `kind` names the file type in messages ("map", "TSDF").
BinaryFileContents readBinaryFile(const std::string& path, const std::string& magic, const std::string& kind,
                                  int version);
// The same for a reader of several format versions, oldest_version..newest_version.
BinaryFileContents readBinaryFile(const std::string& path, const std::string& magic, const std::string& kind,
                                  int oldest_version, int newest_version);

}  // namespace vitamin_e
