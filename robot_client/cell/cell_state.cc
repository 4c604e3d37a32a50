#include "robot_client/cell/cell_state.h"

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"

namespace cornerpose::robot_client {

const char* CellStateName(CellState state) {
  switch (state) {
    case CellState::kStarting:
      return "STARTING";
    case CellState::kIdle:
      return "IDLE";
    case CellState::kPicking:
      return "PICKING";
    case CellState::kStopped:
      return "STOPPED";
    case CellState::kFinished:
      return "FINISHED";
  }
  return "UNKNOWN";
}

const char* PickOutcomeName(PickOutcome outcome) {
  switch (outcome) {
    case PickOutcome::kCompleted:
      return "COMPLETED";
    case PickOutcome::kProtectiveStop:
      return "PROTECTIVE_STOP";
    case PickOutcome::kRuntimeException:
      return "RUNTIME_EXCEPTION";
    case PickOutcome::kConnectionLost:
      return "CONNECTION_LOST";
    case PickOutcome::kDryRun:
      return "DRY_RUN";
    case PickOutcome::kTimeout:
      return "TIMEOUT";
  }
  return "UNKNOWN";
}

std::string DescribePick(const PickRecord& pick) {
  const auto xyz = [](const Eigen::Isometry3d& pose) {
    const Eigen::Vector3d p = pose.translation();
    return absl::StrFormat("(%.3f, %.3f, %.3f)", p.x(), p.y(), p.z());
  };
  std::string line = absl::StrFormat(
      "pick %d %s: %s#%d box at %s score %.2f -> slot %d: %s (plan %.1f ms, program %.1f s)",
      pick.pick_id, pick.program_name, pick.source, pick.frame_id, xyz(pick.plan.box.base_T_box),
      pick.score, pick.plan.slot, PickOutcomeName(pick.outcome), pick.plan_ms, pick.program_s);
  if (pick.outcome != PickOutcome::kCompleted && !pick.detail.empty()) {
    absl::StrAppend(&line, ": ", pick.detail);
  }
  absl::StrAppend(&line, "\n    I ", xyz(pick.plan.initial), "  M ", xyz(pick.plan.approach),
                  "  G ", xyz(pick.plan.grasp), "  R ", xyz(pick.plan.retrieve), "  F ",
                  xyz(pick.plan.place));
  return line;
}

}  // namespace cornerpose::robot_client
