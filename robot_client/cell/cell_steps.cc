#include "robot_client/cell/cell_steps.h"

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"

namespace cornerpose::robot_client {

std::optional<std::string> FinishedReason(const CellStatusSnapshot& status, int max_picks) {
  if (status.next_slot >= status.num_slots) return "the place pattern is full";
  if (max_picks > 0 && status.picks_done >= max_picks) {
    return absl::StrCat("made max_picks (", max_picks, ")");
  }
  return std::nullopt;
}

std::string DescribeRejections(const PickSelection& selection) {
  if (selection.verdicts.empty()) return "no boxes detected";
  std::vector<std::string> reasons;
  for (const BoxVerdict& v : selection.verdicts) {
    reasons.push_back(absl::StrCat("#", v.index, " ", v.reason));
  }
  return absl::StrCat(selection.verdicts.size(),
                      " boxes, none pickable: ", absl::StrJoin(reasons, "; "));
}

PlannedPick PlanFirstPlannable(
    const PickSelection& selection,
    const std::function<absl::StatusOr<PickPlan>(const BoxInBase&)>& plan) {
  // The best box first; when its waypoints cannot all be reached (a
  // straight move through a singularity, say), the next one.
  PlannedPick out;
  for (int index : selection.ranked) {
    const BoxVerdict& candidate = selection.verdicts[static_cast<size_t>(index)];
    out.plan = plan(candidate.box);
    if (out.plan.ok()) {
      out.chosen = &candidate;
      return out;
    }
    out.refusals.push_back(absl::StrCat("#", index, " ", out.plan.status().message()));
  }
  return out;
}

}  // namespace cornerpose::robot_client
