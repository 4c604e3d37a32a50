#include "server/service/detection_pool.h"

#include <algorithm>
#include <utility>

namespace cornerpose::server {

DetectionPool::DetectionPool(int num_workers, int max_queued)
    : max_queued_(std::max(0, max_queued)), last_progress_(std::chrono::steady_clock::now()) {
  const int n = std::max(1, num_workers);
  workers_.reserve(n);
  for (int i = 0; i < n; ++i) workers_.emplace_back([this] { WorkerLoop(); });
}

DetectionPool::~DetectionPool() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  ready_.notify_all();
  for (std::thread& worker : workers_) worker.join();
}

bool DetectionPool::TrySubmit(std::function<void()> task) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    // Tasks about to be picked up by an idle worker count as queued until
    // they are, so a burst cannot slip past the bound.
    const int idle = static_cast<int>(workers_.size()) - running_ -
                     (static_cast<int>(queue_.size()) - bounded_queued_);
    if (bounded_queued_ >= max_queued_ + std::max(0, idle)) return false;
    if (queue_.empty() && running_ == 0) last_progress_ = std::chrono::steady_clock::now();
    queue_.push_back({std::move(task), true});
    ++bounded_queued_;
  }
  ready_.notify_one();
  return true;
}

void DetectionPool::Submit(std::function<void()> task) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (queue_.empty() && running_ == 0) last_progress_ = std::chrono::steady_clock::now();
    queue_.push_back({std::move(task), false});
  }
  ready_.notify_one();
}

int DetectionPool::queue_depth() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return static_cast<int>(queue_.size());
}

bool DetectionPool::Stalled(std::chrono::steady_clock::duration limit) const {
  std::lock_guard<std::mutex> lock(mutex_);
  if (queue_.empty() && running_ == 0) return false;
  return std::chrono::steady_clock::now() - last_progress_ > limit;
}

uint64_t DetectionPool::completed() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return completed_;
}

void DetectionPool::WaitIdle() {
  std::unique_lock<std::mutex> lock(mutex_);
  idle_.wait(lock, [this] { return running_ == 0 && queue_.empty(); });
}

int DetectionPool::queued() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return static_cast<int>(queue_.size());
}

void DetectionPool::WorkerLoop() {
  for (;;) {
    std::function<void()> task;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      ready_.wait(lock, [this] { return stopping_ || !queue_.empty(); });
      // Drain before stopping: every queued task finishes an RPC, and an RPC
      // left unfinished would hang the server's shutdown.
      if (queue_.empty()) return;
      task = std::move(queue_.front().run);
      if (queue_.front().bounded) --bounded_queued_;
      queue_.pop_front();
      ++running_;
    }
    task();
    std::lock_guard<std::mutex> lock(mutex_);
    --running_;
    ++completed_;
    last_progress_ = std::chrono::steady_clock::now();
    if (running_ == 0 && queue_.empty()) idle_.notify_all();
  }
}

}  // namespace cornerpose::server
