// The daemon's metrics served on a real HTTP port, for the parser test
// (daemon_metrics_test.py): prints "port N", then reads commands from stdin
// ("pick OUTCOME PROGRAM_S", "state NAME", "detection", "robot up|down")
// and answers each with "ok" once /metrics shows it.
#include <iostream>
#include <mutex>
#include <sstream>
#include <string>

#include "absl/time/clock.h"
#include "common/metrics/metrics_http.h"
#include "robot_client/metrics/daemon_metrics.h"

using cornerpose::robot_client::CellState;
using cornerpose::robot_client::DaemonMetrics;
using cornerpose::robot_client::PickOutcome;
using cornerpose::robot_client::PickRecord;

int main() {
  std::mutex mutex;
  DaemonMetrics::Sample current;  // guarded by mutex
  DaemonMetrics metrics(
      [&] {
        std::lock_guard<std::mutex> lock(mutex);
        return current;
      },
      absl::Milliseconds(20));
  auto http = cornerpose::metrics::MetricsHttpServer::Start("127.0.0.1:0", &metrics.registry());
  if (!http.ok()) {
    std::cerr << http.status() << "\n";
    return 1;
  }
  std::cout << "port " << (*http)->port() << std::endl;
  std::string line;
  while (std::getline(std::cin, line)) {
    std::istringstream in(line);
    std::string command, arg;
    in >> command >> arg;
    if (command == "pick") {
      PickRecord pick;
      const std::pair<const char*, PickOutcome> outcomes[] = {
          {"COMPLETED", PickOutcome::kCompleted}, {"PROTECTIVE_STOP", PickOutcome::kProtectiveStop},
          {"TIMEOUT", PickOutcome::kTimeout}};
      for (const auto& [name, outcome] : outcomes) {
        if (arg == name) pick.outcome = outcome;
      }
      in >> pick.program_s;
      metrics.OnPick(pick);
    } else {
      std::lock_guard<std::mutex> lock(mutex);
      if (command == "state") {
        for (CellState s : {CellState::kStarting, CellState::kIdle, CellState::kPicking,
                            CellState::kStopped, CellState::kFinished}) {
          if (arg == cornerpose::robot_client::CellStateName(s)) current.status.state = s;
        }
      } else if (command == "detection") {
        ++current.detections_received;
      } else if (command == "robot") {
        current.status.robot_connected = arg == "up";
      }
    }
    // Two sampler periods: the change is in the gauges.
    absl::SleepFor(absl::Milliseconds(60));
    std::cout << "ok" << std::endl;
  }
  return 0;
}
