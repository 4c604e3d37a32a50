#include "common/process/frame_memory.h"

#include <malloc.h>

#include <cstdlib>
#include <cstring>

#include "gtest/gtest.h"

namespace cornerpose {
namespace {

// A frame-sized block (a VGA cloud is 3.7 MB) comes from the heap, not from
// a fresh mapping, and a second one after it is freed reuses its pages.
TEST(FrameMemoryTest, FrameSizedBlocksComeFromTheHeap) {
  ASSERT_TRUE(KeepFrameMemoryInProcess());
  const size_t mapped_before = mallinfo2().hblks;
  constexpr size_t kFrameBytes = 4 << 20;
  char* block = static_cast<char*>(std::malloc(kFrameBytes));
  ASSERT_NE(block, nullptr);
  std::memset(block, 1, kFrameBytes);
  EXPECT_EQ(mallinfo2().hblks, mapped_before) << "a 4 MB block was mapped on its own";
  std::free(block);
  // Freed, it stays with the process (below the trim threshold) ...
  const size_t free_in_heap = mallinfo2().fordblks;
  EXPECT_GE(free_in_heap, kFrameBytes);
  // ... and the next frame's block is carved from it.
  char* again = static_cast<char*>(std::malloc(kFrameBytes));
  ASSERT_NE(again, nullptr);
  EXPECT_LT(mallinfo2().fordblks, free_in_heap);
  std::free(again);
}

TEST(FrameMemoryTest, ANegativeThresholdIsRefused) {
  EXPECT_FALSE(KeepFrameMemoryInProcess(-1, -1));
  EXPECT_TRUE(KeepFrameMemoryInProcess());
}

}  // namespace
}  // namespace cornerpose
