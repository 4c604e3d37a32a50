// A fixed set of worker threads that run detections off gRPC's callback
// threads. The detector takes tens to hundreds of milliseconds of CPU; run on
// a callback thread it would stall every other RPC, and run unbounded it
// would oversubscribe the cores. Work beyond the workers waits in FIFO order
// in a bounded queue: a request waiting there holds its whole message (up to
// max_message_bytes), so the bound is what keeps memory within the pod's.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace cornerpose::server {

class DetectionPool {
 public:
  // num_workers >= 1: the most detections that run at once. max_queued >= 0:
  // the most tasks TrySubmit lets wait for a worker.
  explicit DetectionPool(int num_workers, int max_queued = 1 << 20);
  // Runs every task still queued, then joins the workers.
  ~DetectionPool();

  DetectionPool(const DetectionPool&) = delete;
  DetectionPool& operator=(const DetectionPool&) = delete;

  // Queues a task unless max_queued TrySubmit tasks already wait; false
  // (task not taken) when the queue is full. What Detect uses. Stream tasks
  // (Submit) wait in the same FIFO but do not count against the bound.
  bool TrySubmit(std::function<void()> task);
  // Queues a task whatever the queue holds. For streams only: each has at
  // most one task queued, and their number is bounded on its own.
  void Submit(std::function<void()> task);
  // Tasks waiting for a worker (not those running); for /metrics.
  int queue_depth() const;

  // True when tasks are queued or running and none has finished (or
  // started on an idle pool) for longer than `limit`: the pool is wedged.
  bool Stalled(std::chrono::steady_clock::duration limit) const;
  // Blocks until no task waits or runs.
  void WaitIdle();
  // Tasks finished since the pool started, and tasks waiting now.
  uint64_t completed() const;
  int queued() const;

 private:
  void WorkerLoop();

  const int max_queued_;
  mutable std::mutex mutex_;
  std::condition_variable ready_;
  std::condition_variable idle_;
  struct Task {
    std::function<void()> run;
    bool bounded;  // from TrySubmit: counts against max_queued_
  };
  std::deque<Task> queue_;  // guarded by mutex_
  int bounded_queued_ = 0;  // guarded by mutex_
  int running_ = 0;                          // guarded by mutex_
  uint64_t completed_ = 0;                   // guarded by mutex_
  // When a task last finished, or work arrived at an idle pool.
  std::chrono::steady_clock::time_point last_progress_;  // guarded by mutex_
  bool stopping_ = false;                                // guarded by mutex_
  std::vector<std::thread> workers_;
};

}  // namespace cornerpose::server
