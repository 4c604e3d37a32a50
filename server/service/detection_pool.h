// A fixed set of worker threads that run detections off gRPC's callback
// threads. The detector takes tens to hundreds of milliseconds of CPU; run on
// a callback thread it would stall every other RPC, and run unbounded it
// would oversubscribe the cores. Work beyond the workers waits in FIFO order.
#pragma once

#include <condition_variable>
#include <deque>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace cornerpose::server {

class DetectionPool {
 public:
  // num_workers >= 1: the most detections that run at once.
  explicit DetectionPool(int num_workers);
  // Runs every task still queued, then joins the workers.
  ~DetectionPool();

  DetectionPool(const DetectionPool&) = delete;
  DetectionPool& operator=(const DetectionPool&) = delete;

  // Queues a task; it runs on a worker when one is free.
  void Submit(std::function<void()> task);

 private:
  void WorkerLoop();

  std::mutex mutex_;
  std::condition_variable ready_;
  std::deque<std::function<void()>> queue_;  // guarded by mutex_
  bool stopping_ = false;                    // guarded by mutex_
  std::vector<std::thread> workers_;
};

}  // namespace cornerpose::server
