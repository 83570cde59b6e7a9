#include "vitamin_e/common/allocator.h"

#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include <climits>

namespace vitamin_e {

AllocatorSetting reuseFreedFrameBuffers(std::size_t max_buffer_bytes) {
  AllocatorSetting s;
  const std::string mib = std::to_string(max_buffer_bytes >> 20) + " MiB";
#if defined(__GLIBC__)
  if (max_buffer_bytes == 0 || max_buffer_bytes > static_cast<std::size_t>(INT_MAX)) {
    s.what = "allocator unchanged: a buffer size of " + std::to_string(max_buffer_bytes) + " bytes";
    return s;
  }
  const int bytes = static_cast<int>(max_buffer_bytes);
  // Both values fixed: glibc then also stops adapting them (its dynamic threshold).
  if (mallopt(M_MMAP_THRESHOLD, bytes) != 1 || mallopt(M_TRIM_THRESHOLD, bytes) != 1) {
    s.what = "allocator unchanged: glibc refused a threshold of " + mib;
    return s;
  }
  s.applied = true;
  s.what = "buffers up to " + mib + " from the heap; freed memory kept for reuse up to " + mib + " per heap";
#else
  (void)max_buffer_bytes;
  s.what = "allocator unchanged: not glibc";
#endif
  return s;
}

}  // namespace vitamin_e
