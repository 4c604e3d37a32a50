// Choosing which detected box to pick: the boxes of one frame, moved to the
// base frame, filtered (score, grasp face tilt, workspace, reachability) and
// ordered topmost first, then by score.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "common/box/box_types.h"
#include "robot_client/config/robot_config.h"
#include "robot_client/planning/grasp_geometry.h"

namespace cornerpose::robot_client {

// What selection made of one detected box.
struct BoxVerdict {
  int index = -1;  // into the input boxes
  bool accepted = false;
  // Why it was rejected (for the log), empty when accepted, e.g.
  // "grasp face tilted 41.2 deg from base +z (max 30.0)".
  std::string reason;
  BoxInBase box;  // the box in the base frame
  double score = 0.0;
};

struct PickSelection {
  // Index into the input boxes of the box to pick; none when every box was
  // rejected or there were none.
  std::optional<int> chosen;
  // Indices of the accepted boxes, best first (chosen == ranked.front()):
  // the next one to try when planning the chosen one fails.
  std::vector<int> ranked;
  // One per input box, in input order.
  std::vector<BoxVerdict> verdicts;
};

// Rejects, in this order, a box whose score is below selection.min_score,
// whose grasp face normal is more than selection.max_grasp_tilt_deg from
// base +z, or for which none of the four grasps (GraspCandidates) has G, M =
// G + d z and R = G + h z inside `workspace` and reachable. Among the rest
// chooses the highest grasp point; grasp points within
// selection.height_tie_m of the highest are ties, decided by the higher
// score (then the higher point, then the lower index). `ranked` repeats
// that choice on the boxes not yet ranked. `recent_depths` are the grasp
// depths (BoxInBase::depth_m) of the cell's completed picks, oldest first:
// the last selection.face_check_history of them vote in the face check.
PickSelection SelectPick(const std::vector<DetectedBox>& boxes,
                         const Eigen::Isometry3d& base_T_camera, const BoxDims& dims,
                         const SelectionOptions& selection, const Workspace& workspace,
                         const WaypointOptions& waypoints, const Reachability& reachable,
                         const std::vector<double>& recent_depths = {});

}  // namespace cornerpose::robot_client
