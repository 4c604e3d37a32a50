// A minimal fork-join over index ranges: the detector's loops are short and
// uniform, so static chunking on a few std::threads is all they need.
#pragma once

#include <algorithm>
#include <atomic>
#include <functional>
#include <mutex>
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

// Threads kept for many short fork-joins (a loop that runs a few dozen times
// per frame, each run tens of microseconds: too short to start threads for,
// or to wake a sleeping one, which takes as long on a VM). Run(n, fn) calls
// fn(thread_index, begin, end) on `threads` contiguous chunks of [0, n),
// chunk 0 on the caller's thread, and returns when all are done. Between
// runs the helpers spin (yielding) rather than sleep: keep one only for the
// stretch of work that uses it.
class ForkJoin {
 public:
  explicit ForkJoin(int threads) {
    for (int t = 1; t < threads; ++t) helpers_.emplace_back([this, t] { Serve(t); });
  }
  ~ForkJoin() {
    stop_.store(true, std::memory_order_release);
    for (std::thread& h : helpers_) h.join();
  }
  ForkJoin(const ForkJoin&) = delete;
  ForkJoin& operator=(const ForkJoin&) = delete;

  int threads() const { return static_cast<int>(helpers_.size()) + 1; }

  template <typename Fn>
  void Run(int n, Fn&& fn) {
    const int threads = this->threads();
    if (threads == 1 || n < 2) {
      fn(0, 0, n);
      return;
    }
    const std::function<void(int, int, int)> f = std::ref(fn);
    fn_ = &f;
    n_ = n;
    pending_.store(threads - 1, std::memory_order_relaxed);
    generation_.fetch_add(1, std::memory_order_release);
    fn(0, 0, Bound(n, 1, threads));
    while (pending_.load(std::memory_order_acquire) != 0) std::this_thread::yield();
  }

 private:
  static int Bound(int n, int t, int threads) {
    return static_cast<int>(static_cast<long long>(n) * t / threads);
  }
  void Serve(int t) {
    long long seen = 0;
    while (!stop_.load(std::memory_order_acquire)) {
      const long long g = generation_.load(std::memory_order_acquire);
      if (g == seen) {
        std::this_thread::yield();
        continue;
      }
      seen = g;
      const int threads = this->threads();
      (*fn_)(t, Bound(n_, t, threads), Bound(n_, t + 1, threads));
      pending_.fetch_sub(1, std::memory_order_acq_rel);
    }
  }

  std::vector<std::thread> helpers_;
  const std::function<void(int, int, int)>* fn_ = nullptr;
  int n_ = 0;
  std::atomic<int> pending_{0};
  std::atomic<long long> generation_{0};
  std::atomic<bool> stop_{false};
};

// Short parallel loops run by one thread and shared with any thread that
// offers to help while they run (a thread done with its own stage): each
// loop is cut into chunks claimed one at a time, by the caller and by
// whoever helps, so a loop's result must not depend on which thread ran a
// chunk. With no helper a loop simply runs on the caller.
class SharedLoops {
 public:
  SharedLoops() = default;
  SharedLoops(const SharedLoops&) = delete;
  SharedLoops& operator=(const SharedLoops&) = delete;

  // fn(begin, end) over [0, n) in chunks of `chunk`; returns when all are done.
  template <typename Fn>
  void Run(int n, int chunk, Fn&& fn) {
    if (n <= 0) return;
    const std::function<void(int, int)> f = std::ref(fn);
    Loop loop{&f, n, std::max(1, chunk)};
    {
      std::lock_guard<std::mutex> lock(mutex_);
      loop_ = &loop;
      ++generation_;
    }
    Work(loop);
    while (loop.done.load(std::memory_order_acquire) < n) std::this_thread::yield();
    {
      std::lock_guard<std::mutex> lock(mutex_);
      loop_ = nullptr;
    }
    // A helper that took the loop may still be between its last claim (which
    // found nothing left) and letting go of it.
    while (loop.users.load(std::memory_order_acquire) != 0) std::this_thread::yield();
  }

  // Takes chunks of the loops that Run publishes, until Close().
  void Help() {
    long long seen = 0;
    while (!closed_.load(std::memory_order_acquire)) {
      Loop* loop = nullptr;
      {
        std::lock_guard<std::mutex> lock(mutex_);
        if (loop_ != nullptr && generation_ != seen) {
          loop = loop_;
          seen = generation_;
          loop->users.fetch_add(1, std::memory_order_acq_rel);
        }
      }
      if (loop == nullptr) {
        std::this_thread::yield();
        continue;
      }
      Work(*loop);
      loop->users.fetch_sub(1, std::memory_order_acq_rel);
    }
  }

  // Help returns (now, or after its current chunk).
  void Close() { closed_.store(true, std::memory_order_release); }

 private:
  struct Loop {
    const std::function<void(int, int)>* fn;
    int n;
    int chunk;
    std::atomic<int> next{0};
    std::atomic<int> done{0};
    std::atomic<int> users{0};
  };
  static void Work(Loop& loop) {
    for (int i = loop.next.fetch_add(loop.chunk); i < loop.n; i = loop.next.fetch_add(loop.chunk)) {
      const int end = std::min(loop.n, i + loop.chunk);
      (*loop.fn)(i, end);
      loop.done.fetch_add(end - i, std::memory_order_acq_rel);
    }
  }

  std::mutex mutex_;
  Loop* loop_ = nullptr;      // guarded by mutex_
  long long generation_ = 0;  // guarded by mutex_
  std::atomic<bool> closed_{false};
};

}  // namespace cornerpose::internal
