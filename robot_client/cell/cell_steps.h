// The decisions of one pass of the cell's loop (CellController::Step) that
// need no robot, no stream and no clock, so each has a unit test: whether
// the cell is done, which ranked box is the first that plans, and how a
// frame's refusals read in the log.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "robot_client/cell/cell_state.h"
#include "robot_client/planning/pick_plan.h"
#include "robot_client/planning/pick_selection.h"

namespace cornerpose::robot_client {

// Why the cell is finished ("the place pattern is full", "made max_picks
// (N)"), or nullopt while there is a slot and a pick left. max_picks 0 =
// no limit.
std::optional<std::string> FinishedReason(const CellStatusSnapshot& status, int max_picks);

// "3 boxes, none pickable: #0 grasp face tilted ...; #1 ..." ("no boxes
// detected" for none).
std::string DescribeRejections(const PickSelection& selection);

// The first of selection.ranked whose plan succeeds, and its plan; or, when
// none does, every refusal ("#2 straight move ...").
struct PlannedPick {
  const BoxVerdict* chosen = nullptr;  // into selection.verdicts; null when none planned
  absl::StatusOr<PickPlan> plan = absl::NotFoundError("no box");
  std::vector<std::string> refusals;
};
PlannedPick PlanFirstPlannable(
    const PickSelection& selection,
    const std::function<absl::StatusOr<PickPlan>(const BoxInBase&)>& plan);

}  // namespace cornerpose::robot_client
