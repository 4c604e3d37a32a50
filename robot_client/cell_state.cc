#include "robot_client/cell_state.h"

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
  const Eigen::Vector3d g = pick.plan.grasp.translation();
  const Eigen::Vector3d f = pick.plan.place.translation();
  std::string line = absl::StrFormat(
      "pick %d %s: %s#%d score %.2f, grasp G (%.3f, %.3f, %.3f) -> slot %d F (%.3f, %.3f, "
      "%.3f): %s (plan %.1f ms, program %.1f s)",
      pick.pick_id, pick.program_name, pick.source, pick.frame_id, pick.score, g.x(), g.y(), g.z(),
      pick.plan.slot, f.x(), f.y(), f.z(), PickOutcomeName(pick.outcome), pick.plan_ms,
      pick.program_s);
  if (pick.outcome != PickOutcome::kCompleted && !pick.detail.empty()) {
    absl::StrAppend(&line, ": ", pick.detail);
  }
  return line;
}

}  // namespace cornerpose::robot_client
