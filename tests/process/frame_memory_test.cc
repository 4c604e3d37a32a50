#include "common/process/frame_memory.h"

#include <malloc.h>

#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <thread>
#include <vector>

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
  EXPECT_FALSE(KeepFrameMemoryInProcess(1 << 20, 1 << 20, 0));
  EXPECT_TRUE(KeepFrameMemoryInProcess());
}

// The arenas glibc made, from malloc_info's report (one <heap> per arena).
int Arenas() {
  char* text = nullptr;
  size_t size = 0;
  FILE* out = open_memstream(&text, &size);
  if (out == nullptr) return -1;
  malloc_info(0, out);
  std::fclose(out);
  int heaps = 0;
  for (const char* p = text; (p = std::strstr(p, "<heap nr=")) != nullptr; ++p) ++heaps;
  std::free(text);
  return heaps;
}

// Eight threads holding a frame-sized block at once share the two arenas
// (glibc alone would give most of them one of their own, each keeping its
// freed frame).
TEST(FrameMemoryTest, ThreadsShareAFewArenas) {
  ASSERT_TRUE(KeepFrameMemoryInProcess());
  constexpr int kThreads = 8;
  std::mutex m;
  std::condition_variable cv;
  int holding = 0;
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t) {
    threads.emplace_back([&] {
      char* block = static_cast<char*>(std::malloc(4 << 20));
      if (block != nullptr) std::memset(block, 1, 4 << 20);
      std::unique_lock<std::mutex> lock(m);
      ++holding;
      cv.notify_all();
      cv.wait(lock, [&] { return holding == kThreads; });
      lock.unlock();
      std::free(block);
    });
  }
  for (std::thread& t : threads) t.join();
  const int arenas = Arenas();
  EXPECT_GE(arenas, 1);
  EXPECT_LE(arenas, 2);
}

}  // namespace
}  // namespace cornerpose
