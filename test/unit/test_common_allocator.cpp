// common/allocator.h: after reuseFreedFrameBuffers() a frame-sized buffer comes from the heap (not
// a mapping of its own) and, freed, stays with the heap for the next frame.
#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>

#include "vitamin_e/common/allocator.h"

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace {

#if defined(__GLIBC__)
// A buffer, touched so that it is really there.
void* touched(std::size_t bytes) {
  void* p = std::malloc(bytes);
  if (p) std::memset(p, 1, bytes);
  return p;
}
#endif

}  // namespace

// (No size above the limit is tried here: glibc 2.36 takes any, and the setting would stay for
// the test below.)
TEST(ReuseFreedFrameBuffers, LeavesTheAllocatorAloneForNoSize) {
  const vitamin_e::AllocatorSetting zero = vitamin_e::reuseFreedFrameBuffers(0);
  EXPECT_FALSE(zero.applied);
  EXPECT_NE(zero.what.find("unchanged"), std::string::npos) << zero.what;
}

TEST(ReuseFreedFrameBuffers, KeepsFrameBuffersOnTheHeap) {
#if !defined(__GLIBC__)
  GTEST_SKIP() << "glibc's allocator only";
#else
  constexpr std::size_t kMiB = std::size_t{1} << 20;
  // Before: glibc maps a 1 MiB buffer on its own (its threshold starts at 128 KiB). Freeing it
  // raises glibc's own threshold to 1 MiB and its trim threshold to 2 MiB: a 24 MiB buffer
  // would still be mapped, and freed, unmapped.
  const std::size_t mapped_before = mallinfo2().hblks;
  void* before = touched(kMiB);
  ASSERT_NE(before, nullptr);
  EXPECT_EQ(mallinfo2().hblks, mapped_before + 1) << "glibc's default no longer maps a 1 MiB buffer";
  std::free(before);

  const vitamin_e::AllocatorSetting s = vitamin_e::reuseFreedFrameBuffers();
  ASSERT_TRUE(s.applied) << s.what;
  EXPECT_NE(s.what.find("32 MiB"), std::string::npos) << s.what;

  // After: the same buffer from the heap, and freed, the heap keeps it.
  const std::size_t mapped = mallinfo2().hblks;
  void* frame = touched(24 * kMiB);
  ASSERT_NE(frame, nullptr);
  EXPECT_EQ(mallinfo2().hblks, mapped);
  std::free(frame);
  EXPECT_GE(mallinfo2().fordblks, 24 * kMiB);
  // The next frame's buffer reuses that memory: the heap does not grow.
  const std::size_t heap = mallinfo2().arena;
  void* next = touched(24 * kMiB);
  ASSERT_NE(next, nullptr);
  EXPECT_EQ(mallinfo2().arena, heap);
  std::free(next);
#endif
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
