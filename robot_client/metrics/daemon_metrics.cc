#include "robot_client/metrics/daemon_metrics.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <utility>
#include <vector>

#include "absl/time/clock.h"

namespace cornerpose::robot_client {
namespace {

using Samples = std::vector<std::pair<metrics::LabelValues, double>>;

template <typename T>
T* Must(absl::StatusOr<T*> family) {
  // The names are constants: a failure is a programming error.
  if (!family.ok()) {
    std::fprintf(stderr, "DaemonMetrics: %s\n", family.status().ToString().c_str());
    std::abort();
  }
  return *family;
}

void Must(const absl::Status& status) {
  if (!status.ok()) {
    std::fprintf(stderr, "DaemonMetrics: %s\n", status.ToString().c_str());
    std::abort();
  }
}

}  // namespace

DaemonMetrics::DaemonMetrics(std::function<Sample()> sample, absl::Duration period)
    : sample_(std::move(sample)) {
  picks_ = Must(registry_.AddCounter("cornerpose_cell_picks_total",
                                     "Picks ended, by outcome (COMPLETED, PROTECTIVE_STOP, ...)",
                                     {"outcome"}));
  for (PickOutcome o : {PickOutcome::kCompleted, PickOutcome::kProtectiveStop,
                        PickOutcome::kRuntimeException, PickOutcome::kConnectionLost,
                        PickOutcome::kDryRun, PickOutcome::kTimeout}) {
    picks_->WithLabels({PickOutcomeName(o)});  // every series from the start
  }
  cycle_seconds_ = Must(registry_.AddHistogram(
      "cornerpose_cell_cycle_seconds", "Time from one pick's end to the next one's",
      {}, metrics::DefaultSecondsBuckets()));
  program_seconds_ = Must(registry_.AddHistogram(
      "cornerpose_cell_program_seconds", "A pick program's time from send to its end", {},
      metrics::DefaultSecondsBuckets()));
  Must(registry_.AddGaugeCallback(
      "cornerpose_cell_state", "1 for the cell's current state, 0 for the others", {"state"},
      [this] {
        std::lock_guard<std::mutex> lock(mutex_);
        Samples out;
        for (CellState s : {CellState::kStarting, CellState::kIdle, CellState::kPicking,
                            CellState::kStopped, CellState::kFinished}) {
          out.push_back({{CellStateName(s)}, s == last_.status.state ? 1.0 : 0.0});
        }
        return out;
      }));
  Must(registry_.AddGaugeCallback(
      "cornerpose_cell_link_up", "1 while a link is connected (perception, robot)", {"link"},
      [this] {
        std::lock_guard<std::mutex> lock(mutex_);
        return Samples{{{"perception"}, last_.status.perception_connected ? 1.0 : 0.0},
                       {{"robot"}, last_.status.robot_connected ? 1.0 : 0.0}};
      }));
  Must(registry_.AddGaugeCallback(
      "cornerpose_cell_link_age_seconds",
      "perception: seconds since the last detection arrived (since start before the first); "
      "robot: seconds since the controller connection was last up (+Inf: never)",
      {"link"}, [this] {
        std::lock_guard<std::mutex> lock(mutex_);
        const absl::Time now = absl::Now();
        const double robot = last_.status.robot_connected
                                 ? 0.0
                                 : (last_robot_up == absl::InfinitePast()
                                        ? INFINITY
                                        : absl::ToDoubleSeconds(now - last_robot_up));
        return Samples{{{"perception"}, absl::ToDoubleSeconds(now - last_detection)},
                       {{"robot"}, robot}};
      }));
  SampleOnce();
  thread_ = std::thread([this, period] {
    std::unique_lock<std::mutex> lock(mutex_);
    while (!stop_.wait_for(lock, absl::ToChronoNanoseconds(period), [this] { return stopping_; })) {
      lock.unlock();
      SampleOnce();
      lock.lock();
    }
  });
}

DaemonMetrics::~DaemonMetrics() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  stop_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void DaemonMetrics::SampleOnce() {
  const Sample now = sample_();  // outside the lock: it takes the cell's
  std::lock_guard<std::mutex> lock(mutex_);
  const absl::Time t = absl::Now();
  if (now.detections_received != last_.detections_received) last_detection = t;
  if (now.status.robot_connected) last_robot_up = t;
  last_ = now;
}

void DaemonMetrics::OnPick(const PickRecord& pick) {
  picks_->WithLabels({PickOutcomeName(pick.outcome)}).Increment();
  program_seconds_->WithLabels({}).Observe(pick.program_s);
  std::lock_guard<std::mutex> lock(mutex_);
  const absl::Time t = absl::Now();
  if (last_pick_end != absl::InfinitePast()) {
    cycle_seconds_->WithLabels({}).Observe(absl::ToDoubleSeconds(t - last_pick_end));
  }
  last_pick_end = t;
}

}  // namespace cornerpose::robot_client
