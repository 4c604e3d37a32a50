// What the daemon reports about the cell: its state, and one record per pick
// (served by the status service, printed as picks happen).
#pragma once

#include <cstdint>
#include <string>

#include "absl/time/time.h"
#include "robot_client/planning/pick_plan.h"

namespace cornerpose::robot_client {

enum class CellState { kStarting, kIdle, kPicking, kStopped, kFinished };
// "STARTING", "IDLE", "PICKING", "STOPPED", "FINISHED".
const char* CellStateName(CellState state);

struct CellStatusSnapshot {
  CellState state = CellState::kStarting;
  // Why the cell is STOPPED (or FINISHED).
  std::string stop_reason;
  int picks_done = 0;
  int picks_failed = 0;
  int next_slot = 0;
  int num_slots = 0;
  bool perception_connected = false;
  bool robot_connected = false;
  bool dry_run = false;
  // Waiting for an operator's AcknowledgeFault.
  bool awaiting_acknowledgement = false;
  // The pick whose end is unknown; 0: none.
  uint64_t unknown_pick_id = 0;
  // "operator at time: note" of the last acknowledgement.
  std::string last_acknowledgement;
};

enum class PickOutcome {
  kCompleted,
  kProtectiveStop,
  kRuntimeException,
  kConnectionLost,
  kDryRun,
  kTimeout,
  // The program's end is unknown (timeout, lost / stale link, stopped
  // before its done message): needs an operator's acknowledgement.
  kUnknown,
};
// "COMPLETED", "PROTECTIVE_STOP", ...
const char* PickOutcomeName(PickOutcome outcome);

struct PickRecord {
  uint64_t pick_id = 0;
  std::string program_name;
  // The frame the box was detected in.
  std::string source;
  // Whether that source is a live camera (not a replay of recorded frames).
  bool source_live = false;
  uint64_t frame_id = 0;
  absl::Time capture_time;
  double score = 0.0;
  // The waypoints, the box in the base frame and the slot.
  PickPlan plan;
  PickOutcome outcome = PickOutcome::kCompleted;
  std::string detail;
  double plan_ms = 0.0;
  double program_s = 0.0;
  absl::Time start_time;
};

// Two lines for the log: "pick 3 pick_0003: cell#12 box at (x, y, z) score
// 0.93 -> slot 2: COMPLETED (plan 0.2 ms, program 7.9 s)" and the positions
// of the waypoints I, M, G, R, F (base frame, metres).
std::string DescribePick(const PickRecord& pick);

}  // namespace cornerpose::robot_client
