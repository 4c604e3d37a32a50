#include "robot_client/cell/cell_steps.h"

#include <algorithm>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
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

bool StillThere(const PickSelection& selection, const Eigen::Vector3d& grasp_point,
                double tolerance_m) {
  return std::any_of(
      selection.verdicts.begin(), selection.verdicts.end(),
      [&](const BoxVerdict& v) { return (v.box.grasp_point - grasp_point).norm() <= tolerance_m; });
}

void DeclineNotLifted(const std::vector<NotLifted>& not_lifted, double tolerance_m,
                      PickSelection* selection) {
  for (BoxVerdict& v : selection->verdicts) {
    if (!v.accepted) continue;
    for (const NotLifted& n : not_lifted) {
      if ((v.box.grasp_point - n.grasp_point).norm() > tolerance_m) continue;
      v.accepted = false;
      v.reason = absl::StrFormat(
          "a pick at (%.3f, %.3f, %.3f) left this box where it was: something lies on it, or "
          "the cup did not seal",
          n.grasp_point.x(), n.grasp_point.y(), n.grasp_point.z());
      break;
    }
  }
  std::erase_if(selection->ranked,
                [&](int i) { return !selection->verdicts[static_cast<size_t>(i)].accepted; });
  selection->chosen.reset();
  if (!selection->ranked.empty()) selection->chosen = selection->ranked.front();
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
