// A minimal fork-join over index ranges: the detector's loops are short and
// uniform, so static chunking on a few std::threads is all they need.
#pragma once

#include <algorithm>
#include <atomic>
#include <thread>
#include <vector>

namespace cornerpose::internal {

// Calls fn(thread_index, begin, end) for `threads` contiguous chunks of
// [0, n); chunk t runs on its own thread (chunk 0 on the caller's).
template <typename Fn>
void ParallelForRanges(int n, int threads, Fn&& fn) {
  threads = std::max(1, std::min(threads, n));
  if (threads <= 1) {
    fn(0, 0, n);
    return;
  }
  std::vector<std::thread> workers;
  workers.reserve(threads - 1);
  auto bounds = [&](int t) { return static_cast<int>(static_cast<long long>(n) * t / threads); };
  for (int t = 1; t < threads; ++t) {
    workers.emplace_back([&, t] { fn(t, bounds(t), bounds(t + 1)); });
  }
  fn(0, bounds(0), bounds(1));
  for (std::thread& w : workers) w.join();
}

// Calls fn(chunk, begin, end) for the chunks [k * chunk_size, ...) of
// [0, n), on up to `threads` threads that each take the next chunk when done
// with one: for loops whose cost per index is uneven (edge bands gather in
// some rows). Which thread runs a chunk varies; what a chunk computes must
// not depend on it.
template <typename Fn>
void ParallelForChunks(int n, int chunk_size, int threads, Fn&& fn) {
  chunk_size = std::max(1, chunk_size);
  const int chunks = (n + chunk_size - 1) / chunk_size;
  std::atomic<int> next{0};
  auto worker = [&] {
    for (int c = next++; c < chunks; c = next++) {
      fn(c, c * chunk_size, std::min(n, (c + 1) * chunk_size));
    }
  };
  threads = std::max(1, std::min(threads, chunks));
  std::vector<std::thread> workers;
  workers.reserve(threads - 1);
  for (int t = 1; t < threads; ++t) workers.emplace_back(worker);
  worker();
  for (std::thread& w : workers) w.join();
}

}  // namespace cornerpose::internal
