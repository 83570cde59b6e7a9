#include "vitamin_e/common/binary_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cstdio>
#include <fstream>
#include <string_view>

namespace vitamin_e {

std::uint64_t fnv1a64(const char* data, std::size_t size) {
  std::uint64_t h = 0xcbf29ce484222325ull;
  for (std::size_t i = 0; i < size; ++i) {
    h ^= static_cast<unsigned char>(data[i]);
    h *= 0x100000001b3ull;
  }
  return h;
}

std::string BinaryReader::getString(std::size_t max_size) {
  const std::uint32_t n = get<std::uint32_t>();
  if (n > max_size) fail("a text field of " + std::to_string(n) + " bytes (at most " + std::to_string(max_size) + ")");
  need(n);
  std::string s(p_, n);
  p_ += n;
  return s;
}

std::uint64_t BinaryReader::getCount(std::size_t min_item_bytes, const char* items) {
  const std::uint64_t n = get<std::uint64_t>();
  if (min_item_bytes > 0 && n > remaining() / min_item_bytes) {
    fail(std::to_string(n) + " " + items + " do not fit in the " + std::to_string(remaining()) + " bytes left");
  }
  return n;
}

void BinaryReader::fail(const std::string& message) const { throw BinaryFileError(what_ + ": " + message); }

namespace {
bool failWith(std::string* error, const std::string& message) {
  if (error) *error = message;
  return false;
}
}  // namespace

bool writeBinaryFile(const std::string& path, const std::string& header_line, const std::string& payload,
                     std::string* error) {
  if (path.empty()) return failWith(error, "no file name given");
  if (header_line.find('\n') != std::string::npos) return failWith(error, "header line with a newline");
  // The temporary file lives beside the target so that rename() is atomic.
  std::string tmpl = path + ".tmp-XXXXXX";
  std::vector<char> name(tmpl.begin(), tmpl.end());
  name.push_back('\0');
  const int fd = ::mkstemp(name.data());
  if (fd < 0) return failWith(error, "cannot create a temporary file beside '" + path + "': " + std::strerror(errno));
  const std::string tmp(name.data());
  ::fchmod(fd, 0644);
  std::string head = header_line + "\n";
  const std::uint64_t size = payload.size();
  const std::uint64_t sum = fnv1a64(payload.data(), payload.size());
  head.append(reinterpret_cast<const char*>(&size), sizeof(size));
  head.append(reinterpret_cast<const char*>(&sum), sizeof(sum));
  auto write_all = [&](const std::string& s) {
    std::size_t done = 0;
    while (done < s.size()) {
      const ssize_t n = ::write(fd, s.data() + done, s.size() - done);
      if (n < 0) {
        if (errno == EINTR) continue;
        return false;
      }
      done += static_cast<std::size_t>(n);
    }
    return true;
  };
  const bool written = write_all(head) && write_all(payload) && ::fsync(fd) == 0;
  const int saved_errno = errno;
  if (::close(fd) != 0 || !written) {
    ::unlink(tmp.c_str());
    return failWith(error, "cannot write '" + path + "': " + std::strerror(written ? errno : saved_errno));
  }
  if (::rename(tmp.c_str(), path.c_str()) != 0) {
    const int e = errno;
    ::unlink(tmp.c_str());
    return failWith(error, "cannot replace '" + path + "': " + std::strerror(e));
  }
  return true;
}

BinaryFileContents readBinaryFile(const std::string& path, const std::string& magic, const std::string& kind,
                                  int version) {
  return readBinaryFile(path, magic, kind, version, version);
}

BinaryFileContents readBinaryFile(const std::string& path, const std::string& magic, const std::string& kind,
                                  int oldest_version, int newest_version) {
  const std::string what = kind + " file '" + path + "'";
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) throw BinaryFileError(what + ": " + std::strerror(errno));
  if (!S_ISREG(st.st_mode)) throw BinaryFileError(what + ": not a regular file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw BinaryFileError(what + ": cannot open: " + std::strerror(errno));
  std::string data(static_cast<std::size_t>(st.st_size), '\0');
  in.read(&data[0], static_cast<std::streamsize>(data.size()));
  if (static_cast<std::size_t>(in.gcount()) != data.size()) throw BinaryFileError(what + ": read error");
  if (data.empty()) throw BinaryFileError(what + ": the file is empty");
  // The first line must be ours before anything else is read.
  if (data.compare(0, magic.size(), magic) != 0) {
    throw BinaryFileError(what + ": not a vitamin_e " + kind + " file (it does not start with '" + magic + "')");
  }
  // The header line ends within the first 4097 bytes.
  const std::size_t eol = std::string_view(data.data(), std::min<std::size_t>(data.size(), 4097)).find('\n');
  if (eol == std::string_view::npos) throw BinaryFileError(what + ": truncated or damaged header line");
  BinaryFileContents out;
  out.header_line = data.substr(0, eol);
  int found = 0;
  const char* const version_end = out.header_line.data() + out.header_line.size();
  if (std::from_chars(out.header_line.data() + magic.size(), version_end, found).ec != std::errc()) {
    throw BinaryFileError(what + ": damaged header line '" + out.header_line + "'");
  }
  if (found < oldest_version || found > newest_version) {
    const std::string reads = oldest_version == newest_version
                                  ? "v" + std::to_string(newest_version)
                                  : "v" + std::to_string(oldest_version) + " to v" + std::to_string(newest_version);
    throw BinaryFileError(what + ": format v" + std::to_string(found) + " is not supported (this build reads " + reads +
                          ")");
  }
  out.version = found;
  const std::size_t head = eol + 1 + 2 * sizeof(std::uint64_t);
  if (data.size() < head) throw BinaryFileError(what + ": truncated after the header line");
  std::uint64_t size = 0, sum = 0;
  std::memcpy(&size, data.data() + eol + 1, sizeof(size));
  std::memcpy(&sum, data.data() + eol + 1 + sizeof(size), sizeof(sum));
  const std::size_t have = data.size() - head;
  if (size > have) {
    throw BinaryFileError(what + ": truncated (" + std::to_string(have) + " of " + std::to_string(size) +
                          " payload bytes)");
  }
  if (size < have) {
    throw BinaryFileError(what + ": " + std::to_string(have - size) + " bytes of unknown data after the payload");
  }
  data.erase(0, head);
  out.payload = std::move(data);
  if (fnv1a64(out.payload.data(), out.payload.size()) != sum) {
    throw BinaryFileError(what + ": corrupt (the checksum of the data does not match)");
  }
  return out;
}

}  // namespace vitamin_e
