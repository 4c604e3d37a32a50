// What the planner keeps the arm and the held box clear of in free moves
// (movej), and the check itself. Straight moves go into the pile and onto
// the slot by design and are checked for singularities only
// (straight_move.h).
//
// The scene comes from what the daemon knows: the boxes in the frame it
// plans from (each as a column from the floor up to its top: a seen top
// hides a solid pile) and the place pattern's slots filled so far (each a
// block the size of its cell).
#pragma once

#include <Eigen/Geometry>
#include <optional>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "common/box/box_types.h"
#include "robot_client/collision/arm_capsules.h"
#include "robot_client/collision/shapes.h"
#include "robot_client/config/robot_config.h"
#include "robot_client/planning/grasp_geometry.h"
#include "robot_client/ur/kinematics.h"

namespace cornerpose::robot_client {

struct SceneObstacle {
  std::string name;    // "the pile", "placed box in slot 4"
  collision::Obb box;  // base frame
};

struct PlanningScene {
  std::vector<SceneObstacle> obstacles;
};

struct CollisionCheckOptions {
  // The arm's links and the held box keep at least this far from every
  // obstacle during a free move, m, in [0, 0.2]. The real arm's path
  // follows the commanded joints to within millimetres; what this covers is
  // the detector's error on the pile's top and the link envelope's.
  double clearance_m = 0.02;
  // A free move is checked at joint vectors no more than this apart (the
  // largest joint turn between samples), rad, in (0, 0.2]: at the UR5e's
  // reach, 0.02 rad moves the tool at most ~2 cm.
  double max_step_rad = 0.02;
  // The suction tool as a capsule (as in the simulated cell).
  collision::ToolShape tool;

  absl::Status Validate() const;
};

// The scene for picking one of `boxes` (the detected boxes of one frame, in
// the base frame, from one SelectPick) into slot `slot` of `pattern`: a
// column per detected box (its bounds from floor_z_m up to its top: what is
// under a seen top is solid) and a block per filled slot (slots 0 .. slot -
// 1, a cell of the pattern each, layer_height_m tall, shrunk by 5 mm a side
// so that touching cells do not merge; a pattern of one row or column uses
// the largest box side there).
PlanningScene ScenePerPick(const std::vector<BoxInBase>& boxes, const BoxDims& dims,
                           const PlacePatternOptions& pattern, int slot, double floor_z_m);

// Removes the obstacles the arm at joints q comes within the clearance of
// (which CheckFreeMove would refuse at the start of every move): the arm stands where it
// stands, so a detected box it is inside is the arm or its mount seen by
// the camera (a pedestal's top is box-shaped), not something to keep clear of.
void DropWhatTheArmOccupies(ur::ArmModel model, const Eigen::Isometry3d& flange_T_tcp,
                            const ur::Joints& q, const CollisionCheckOptions& options,
                            PlanningScene& scene);

// The box carried in a free move: its size and pose in the tool frame.
struct HeldBox {
  BoxDims dims;
  Eigen::Isometry3d tcp_T_box = Eigen::Isometry3d::Identity();
};

// Checks the joint-space straight line from `from` to `to` (what movej
// runs) at both ends and every max_step_rad in between: every link capsule
// and the held box (if any) at least clearance_m from every obstacle.
// `what` names the move in the error: FAILED_PRECONDITION "free move
// R->place_above: the held box comes within 0.020 m of the pile at (x, y,
// z)" (the TCP's position at the first contact).
absl::Status CheckFreeMove(ur::ArmModel model, const Eigen::Isometry3d& flange_T_tcp,
                           const ur::Joints& from, const ur::Joints& to,
                           const std::optional<HeldBox>& held, const PlanningScene& scene,
                           const CollisionCheckOptions& options, const std::string& what);

}  // namespace cornerpose::robot_client
