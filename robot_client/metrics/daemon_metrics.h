// The robot-cell daemon's Prometheus metrics (its /metrics on
// metrics_listen): picks by outcome, the cycle time (one pick's end to the
// next) and program time histograms, the cell's state, and the age of each
// link (perception: since the last detection arrived; robot: since the
// controller connection was last up). A sampler thread reads the cell and
// the subscriber, so the cell's code carries no metrics.
#pragma once

#include <condition_variable>
#include <functional>
#include <mutex>
#include <thread>

#include "absl/time/time.h"
#include "common/metrics/metrics.h"
#include "robot_client/cell/cell_state.h"

namespace cornerpose::robot_client {

class DaemonMetrics {
 public:
  // What the sampler reads, every `period`.
  struct Sample {
    CellStatusSnapshot status;
    uint64_t detections_received = 0;
  };
  DaemonMetrics(std::function<Sample()> sample, absl::Duration period = absl::Milliseconds(250));
  ~DaemonMetrics();
  DaemonMetrics(const DaemonMetrics&) = delete;
  DaemonMetrics& operator=(const DaemonMetrics&) = delete;

  const metrics::Registry& registry() const { return registry_; }
  // A pick ended (CellCallbacks::on_pick).
  void OnPick(const PickRecord& pick);

 private:
  void SampleOnce();

  metrics::Registry registry_;
  metrics::CounterFamily* picks_;
  metrics::HistogramFamily* cycle_seconds_;
  metrics::HistogramFamily* program_seconds_;
  const std::function<Sample()> sample_;

  mutable std::mutex mutex_;
  std::condition_variable stop_;
  bool stopping_ = false;                          // guarded
  Sample last_;                                    // guarded
  absl::Time last_detection = absl::Now();         // guarded
  absl::Time last_robot_up = absl::InfinitePast();  // guarded
  absl::Time last_pick_end = absl::InfinitePast();  // guarded
  std::thread thread_;
};

}  // namespace cornerpose::robot_client
