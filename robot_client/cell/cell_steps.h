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

// Picks that did not lift their box. `grasp_point` is where the cup went
// (base frame); a box whose grasp point is within `tolerance_m` of it in the
// first frame after the pick is still there: nothing was lifted (something
// lies on it, or the cup did not seal).
struct NotLifted {
  Eigen::Vector3d grasp_point = Eigen::Vector3d::Zero();
};
// True when a box of `selection` has its grasp point within tolerance_m of
// `grasp_point`: the pick there left its box.
bool StillThere(const PickSelection& selection, const Eigen::Vector3d& grasp_point,
                double tolerance_m);
// Declines every accepted box within tolerance_m of a not-lifted pick
// ("a pick at (x, y, z) left this box where it was: something lies on it,
// or the cup did not seal"), taking it out of ranked and chosen.
void DeclineNotLifted(const std::vector<NotLifted>& not_lifted, double tolerance_m,
                      PickSelection* selection);

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
