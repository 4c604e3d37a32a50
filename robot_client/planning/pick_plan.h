// The paper's five pick-and-place waypoints (section 5) for one box, as TCP
// poses in the base frame (what URScript's pose literals carry once the
// program has done set_tcp(tcp_offset)):
//
//   I  the current TCP pose, FK(current joints) * flange_T_tcp
//   M  = G + d * base z         approach point; I -> M is a free move
//   G  the grasp: TCP at the grasp face centre, tool z into the face (along
//      -normal), tool x along one of the face's box axes: of the four, the
//      one needing the least wrist rotation from I; M -> G is straight
//   R  = G + h * base z         retrieve, straight up from G
//   place_above = F + a * base z, reached by a free move from R (through
//      the transit waypoint T when the direct one would pass too close to
//      the scene: see below)
//   F  the place: the TCP pose that puts the held box's bottom centre on the
//      slot, grasped face up, the face's longer side along the slot's x axis
//      (of the two, or four for a square face, such box orientations the one
//      needing the least wrist rotation from G); place_above -> F is straight.
//
// Free moves are joint-space moves (movej to a joint vector) to the IK
// solution on the arm's configuration branch (PickArm::branch_reference:
// same shoulder and elbow as the clear pose) nearest the joints the
// move starts from, each angle within the joint limits, so the arm never
// swings over its shoulder to reach a place behind it. A movel follows the
// straight line (CheckStraightMove). The planner replays the program, so a
// plan it returns has every straight move (M -> G, G -> R, place_above -> F
// and back) clear of singularities and branch flips.
//
// Heights come from the pile when the box carries its top
// (BoxInBase::pile_top_z_m): M at least pile_clearance_m above the pile's
// top, R high enough that the held box's bottom clears it by as much.
//
// Given a planning scene (planning_scene.h), the free moves I -> M and
// R -> place_above are checked along their joint-space path against it (the
// arm's links, and from G on the held box). When R -> place_above is not
// clear — a place lower than R makes the joint-space path sink towards the
// pile on the way out — the program goes through a transit waypoint T above
// the slot, at R's height or higher (R, +0.1, +0.2, +0.3 m, the first whose
// moves R -> T and T -> place_above are clear and reachable).
#pragma once

#include <Eigen/Geometry>
#include <optional>

#include "absl/status/statusor.h"
#include "common/box/box_types.h"
#include "robot_client/config/robot_config.h"
#include "robot_client/planning/grasp_geometry.h"
#include "robot_client/planning/planning_scene.h"
#include "robot_client/planning/straight_move.h"
#include "robot_client/ur/kinematics.h"

namespace cornerpose::robot_client {

struct PickPlan {
  // base_T_tcp of each waypoint.
  Eigen::Isometry3d initial = Eigen::Isometry3d::Identity();      // I
  Eigen::Isometry3d approach = Eigen::Isometry3d::Identity();     // M
  Eigen::Isometry3d grasp = Eigen::Isometry3d::Identity();        // G
  Eigen::Isometry3d retrieve = Eigen::Isometry3d::Identity();     // R
  // T, when the free move R -> place_above needs one (see above).
  std::optional<Eigen::Isometry3d> transit;
  Eigen::Isometry3d place_above = Eigen::Isometry3d::Identity();  // above F
  Eigen::Isometry3d place = Eigen::Isometry3d::Identity();        // F
  // The place pattern slot F fills, and its pose (the box's bottom centre).
  int slot = 0;
  Eigen::Isometry3d base_T_slot = Eigen::Isometry3d::Identity();
  // The box as picked (of size box_dims), and where it ends up (base_T_box
  // at F).
  BoxInBase box;
  BoxDims box_dims;
  Eigen::Isometry3d base_T_box_placed = Eigen::Isometry3d::Identity();
  // The held box in the tool frame, from G on.
  Eigen::Isometry3d tcp_T_box = Eigen::Isometry3d::Identity();
  // Tool rotation I -> G and G -> F, radians in [0, pi].
  double grasp_rotation_rad = 0.0;
  double place_rotation_rad = 0.0;
  // The joints the controller reaches each waypoint with (see above); the
  // return move F -> place_above ends within the straight-move bound of
  // place_above_joints.
  ur::Joints initial_joints{};
  ur::Joints approach_joints{};
  ur::Joints grasp_joints{};
  ur::Joints retrieve_joints{};
  ur::Joints transit_joints{};  // meaningful when transit is set
  ur::Joints place_above_joints{};
  ur::Joints place_joints{};
};

// The arm that runs the plan, and where it is now.
struct PickArm {
  ur::ArmModel model = ur::ArmModel::kUr5e;
  // The TCP in the flange frame (GripperOptions::flange_T_tcp).
  Eigen::Isometry3d flange_T_tcp = Eigen::Isometry3d::Identity();
  // The current joints; I = FK(joints) * flange_T_tcp.
  ur::Joints joints{};
  // The configuration branch every free move stays on (shoulder and elbow:
  // the signs that tell the IK solutions apart up to a wrist flip), given by a
  // joint vector on it, normally the clear pose; unset = that of `joints`.
  std::optional<ur::Joints> branch_reference;
  // How straight moves are checked; linear_speed_m_s should be the
  // program's (MotionOptions::linear_speed_m_s).
  StraightMoveOptions straight_moves;
  // How free moves are checked against the planning scene.
  CollisionCheckOptions free_moves;
};

// Plans the waypoints for `box` (a box of size `dims`, see BoxToBase) into
// the slot at base_T_slot, starting from arm.joints. Tries the grasps in
// order of least wrist rotation from I, and for each the place orientations
// in order of least rotation from G, and returns the first the controller
// can run: M and place_above have an IK solution (the one nearest the
// joints before the movej is taken) and every straight move passes
// CheckStraightMove from the joints the previous move ends with.
// FAILED_PRECONDITION naming the waypoint when one lies outside `workspace`
// (e.g. "waypoint R (retrieve) at (0.100, -0.500, 0.900) is outside the
// workspace ...") or, when no orientation works, naming the first failure
// of the preferred choice: "waypoint M (approach) at (...) is not
// reachable" or "straight move G->R (retrieve) passes a singularity at
// (...): ..." (the moves: M->G (grasp), G->R (retrieve), place_above->F
// (place), F->place_above (leave)), or "free move I->M (approach): the
// wrist_2 comes within 0.020 m of the pile at (...)" when `scene` is given
// and a free move cannot be made clear of it. No scene: free moves are not
// checked for contact.
absl::StatusOr<PickPlan> PlanPick(const PickArm& arm, const BoxInBase& box, const BoxDims& dims,
                                  const Eigen::Isometry3d& base_T_slot, int slot,
                                  const WaypointOptions& waypoints, const Workspace& workspace,
                                  const PlanningScene* scene = nullptr);

// The approach distance d (M = G + d z) and retrieve height h (R = G + h z)
// for `box`: approach_distance_m and retrieve_height_m, raised when the
// box's pile_top_z_m is known and higher: M at least pile_clearance_m above
// the pile's top, R with the held box's bottom pile_clearance_m above it.
double ApproachDistance(const BoxInBase& box, const WaypointOptions& waypoints);
double RetrieveHeight(const BoxInBase& box, const WaypointOptions& waypoints);
// a in place_above = F + a z: place_approach_height_m, raised so the held
// box's bottom arrives pile_clearance_m above the tops of the boxes already
// in its layer (depth_m tall, placed as it will be).
double PlaceApproachHeight(const BoxInBase& box, const WaypointOptions& waypoints);

// The daemon's entry point: PlanPick with the configured arm model, the
// gripper's TCP offset, `current_joints`, the clear pose as the branch
// reference, the motion's linear speed and the
// slot pose from the place pattern (RESOURCE_EXHAUSTED when `slot` is past
// its end), for a box of `dims` (the size the server detected with), with
// free moves checked against `scene` when given.
absl::StatusOr<PickPlan> PlanPickForSlot(const RobotClientOptions& options,
                                         const ur::Joints& current_joints, const BoxInBase& box,
                                         int slot, const BoxDims& dims,
                                         const PlanningScene* scene = nullptr);
// The same for the configured box size, options.perception.box.
absl::StatusOr<PickPlan> PlanPickForSlot(const RobotClientOptions& options,
                                         const ur::Joints& current_joints, const BoxInBase& box,
                                         int slot);

}  // namespace cornerpose::robot_client
