#pragma once
// How the process's allocator treats the per-frame buffers. Every frame makes and frees
// images, curvature and depth maps of 0.3-2 MB (ours and OpenCV's temporaries). glibc's
// defaults map each such buffer from the kernel (mmap above 128 KiB) and hand freed heap
// memory back (trimming above 128 KiB), so the next frame faults every page in again: on
// KITTI 07 that was 115 000 page faults and a tenth of the process's CPU (docs/PERFORMANCE.md,
// "Page faults"). reuseFreedFrameBuffers() takes buffers up to `max_buffer_bytes` from the heap,
// and a heap gives freed memory back to the kernel only beyond that much. The setting is the
// process's: call it once, at start-up (vitamin_e_run, the nodelets).
#include <cstddef>
#include <string>

namespace vitamin_e {

struct AllocatorSetting {
  bool applied = false;  // false: not glibc, a size of 0 or above INT_MAX, or glibc refused it
  std::string what;      // what was set, or why nothing was
};

// 32 MiB: a 4096 x 2048 float image still fits; larger, rarer blocks keep their own mapping
// rather than splitting the heap.
inline constexpr std::size_t kFrameBufferBytes = std::size_t{32} << 20;

AllocatorSetting reuseFreedFrameBuffers(std::size_t max_buffer_bytes = kFrameBufferBytes);

}  // namespace vitamin_e
