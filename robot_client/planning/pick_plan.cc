#include "robot_client/planning/pick_plan.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "robot_client/planning/place_pattern.h"

namespace cornerpose::robot_client {
namespace {

// In-face sides within this of each other make a square face: four place
// orientations instead of two.
constexpr double kSquareToleranceM = 1e-3;
constexpr double kTwoPi = 2.0 * 3.14159265358979323846;

std::string Xyz(const Eigen::Vector3d& p) {
  return absl::StrFormat("(%.3f, %.3f, %.3f)", p.x(), p.y(), p.z());
}

// slot_T_box for every allowed place orientation of the box: grasp face up
// (its normal along slot z), bottom centre at the slot origin, the face's
// longer side along slot +-x.
std::vector<Eigen::Isometry3d> PlaceOrientations(BoxFace face, const BoxDims& dims) {
  const int axis = static_cast<int>(face) / 2;
  const int a = (axis + 1) % 3;
  const int b = (axis + 2) % 3;
  const bool square = std::abs(dims[a] - dims[b]) < kSquareToleranceM;
  const int longer = dims[b] > dims[a] + kSquareToleranceM ? b : a;
  const Eigen::Vector3d n = BoxFaceNormal(face);
  const Eigen::Vector3d l = Eigen::Vector3d::Unit(longer);
  Eigen::Matrix3d slot_R_box;
  slot_R_box.row(0) = l.transpose();
  slot_R_box.row(1) = n.cross(l).transpose();
  slot_R_box.row(2) = n.transpose();
  std::vector<Eigen::Isometry3d> out;
  for (int quarter = 0; quarter < 4; quarter += square ? 1 : 2) {
    Eigen::Isometry3d slot_T_box = Eigen::Isometry3d::Identity();
    slot_T_box.linear() =
        Eigen::AngleAxisd(quarter * 0.5 * 3.14159265358979323846, Eigen::Vector3d::UnitZ())
            .toRotationMatrix() *
        slot_R_box;
    slot_T_box.translation() = Eigen::Vector3d(0, 0, 0.5 * dims[axis]);
    out.push_back(slot_T_box);
  }
  return out;
}

double RotationBetween(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return ur::RotationAngleBetween(Eigen::Quaterniond(a.linear()), Eigen::Quaterniond(b.linear()));
}

}  // namespace

double ApproachDistance(const BoxInBase& box, const WaypointOptions& waypoints) {
  if (!std::isfinite(box.pile_top_z_m)) return waypoints.approach_distance_m;
  return std::max(waypoints.approach_distance_m,
                  box.pile_top_z_m + waypoints.pile_clearance_m - box.grasp_point.z());
}

double RetrieveHeight(const BoxInBase& box, const WaypointOptions& waypoints) {
  if (!std::isfinite(box.pile_top_z_m)) return waypoints.retrieve_height_m;
  // The held box's bottom (depth_m below the cup) clear of the pile's top:
  // a low box next to a high one is lifted past it before the free move.
  return std::max(waypoints.retrieve_height_m, box.pile_top_z_m + waypoints.pile_clearance_m +
                                                   box.depth_m - box.grasp_point.z());
}

double PlaceApproachHeight(const BoxInBase& box, const WaypointOptions& waypoints) {
  // The boxes already in the slot's layer are as tall as this one placed
  // grasp face up: the free move must bring its bottom in above their tops.
  return std::max(waypoints.place_approach_height_m, box.depth_m + waypoints.pile_clearance_m);
}

namespace {

// The waypoints of one choice of grasp and place orientation.
PickPlan Waypoints(const Eigen::Isometry3d& initial, const BoxInBase& box, const BoxDims& dims,
                   const Eigen::Isometry3d& grasp, const Eigen::Isometry3d& base_T_slot,
                   const Eigen::Isometry3d& slot_T_box, int slot,
                   const WaypointOptions& waypoints) {
  PickPlan plan;
  plan.initial = initial;
  plan.grasp = grasp;
  plan.approach = RaisedAlongBaseZ(grasp, ApproachDistance(box, waypoints));
  plan.retrieve = RaisedAlongBaseZ(grasp, RetrieveHeight(box, waypoints));
  plan.slot = slot;
  plan.base_T_slot = base_T_slot;
  plan.box = box;
  plan.box_dims = dims;
  plan.tcp_T_box = grasp.inverse() * box.base_T_box;
  plan.base_T_box_placed = base_T_slot * slot_T_box;
  plan.place = plan.base_T_box_placed * plan.tcp_T_box.inverse();
  plan.place_above = RaisedAlongBaseZ(plan.place, PlaceApproachHeight(box, waypoints));
  plan.grasp_rotation_rad = RotationBetween(initial, grasp);
  plan.place_rotation_rad = RotationBetween(grasp, plan.place);
  return plan;
}

// The commanded waypoints with their names, in program order.
std::vector<std::pair<const char*, const Eigen::Isometry3d*>> Commanded(const PickPlan& plan) {
  return {{"M (approach)", &plan.approach},
          {"G (grasp)", &plan.grasp},
          {"R (retrieve)", &plan.retrieve},
          {"place_above", &plan.place_above},
          {"F (place)", &plan.place}};
}

// The configuration branch of a joint vector: which of the (up to 8) IK
// solutions of one flange pose it is. reach: the wrist centre in front of
// (+1) or behind (-1) the shoulder along the arm's heading (behind = the
// upper arm over the shoulder); elbow: sign of q3. These two decide where
// the upper and lower arm sweep, so free moves keep them; the wrist (sign of
// sin q5) may flip in a free move (q4, q6 turn by pi: a local motion), but
// the joint-space cost below makes a flip the last resort.
struct Branch {
  int reach = 1, elbow = 1;
  bool operator==(const Branch&) const = default;
};

int Sign(double v) { return v < 0.0 ? -1 : 1; }

Branch BranchOf(ur::ArmModel model, const ur::Joints& q) {
  const ur::DhParameters& dh = ur::NominalDh(model);
  // Horizontal reach of the wrist from the shoulder in the arm's plane (UR
  // DH: a2, a3 < 0, so a straight arm pointing along the heading has q2 = pi).
  const double reach = -(dh.a[1] * std::cos(q[1]) + dh.a[2] * std::cos(q[1] + q[2]));
  return {Sign(reach), Sign(std::remainder(q[2], kTwoPi))};
}

// `angle` shifted by 2 pi multiples to the value nearest `near` within
// +-limit; nullopt when none is.
std::optional<double> NearestTurn(double angle, double near, double limit) {
  const double base = near + std::remainder(angle - near, kTwoPi);
  for (double v : {base, base - kTwoPi, base + kTwoPi}) {
    if (std::abs(v) <= limit) return v;
  }
  return std::nullopt;
}

// The joints a movej to `pose` ends with: the program commands the IK
// solution on the reference branch nearest `from` (Euclidean in joint
// space), each angle the turn nearest `from` within the joint limits.
absl::Status FreeMove(const PickArm& arm, const char* name, const Eigen::Isometry3d& pose,
                      const ur::Joints& from, ur::Joints* to) {
  const ur::IkOptions ik;
  const std::vector<ur::Joints> solutions =
      ur::InverseKinematicsAll(arm.model, pose * arm.flange_T_tcp.inverse(), ik);
  if (solutions.empty()) {
    return absl::FailedPreconditionError(
        absl::StrFormat("waypoint %s at %s is not reachable", name, Xyz(pose.translation())));
  }
  const Branch want = BranchOf(arm.model, arm.branch_reference.value_or(arm.joints));
  double best_cost = std::numeric_limits<double>::infinity();
  for (const ur::Joints& solution : solutions) {
    if (!(BranchOf(arm.model, solution) == want)) continue;
    ur::Joints q{};
    bool within = true;
    double cost = 0.0;
    for (int i = 0; i < 6 && within; ++i) {
      const std::optional<double> v = NearestTurn(solution[i], from[i], ik.joint_limit_rad);
      if (!v) {
        within = false;
        break;
      }
      q[i] = *v;
      cost += (q[i] - from[i]) * (q[i] - from[i]);
    }
    if (within && cost < best_cost) {
      best_cost = cost;
      *to = q;
    }
  }
  if (!std::isfinite(best_cost)) {
    return absl::FailedPreconditionError(absl::StrFormat(
        "waypoint %s at %s is reachable only on another configuration branch (shoulder or "
        "elbow flipped from the clear pose's)",
        name, Xyz(pose.translation())));
  }
  return absl::OkStatus();
}

absl::Status StraightMove(const PickArm& arm, const char* name, const Eigen::Isometry3d& from,
                          const Eigen::Isometry3d& to, const ur::Joints& from_joints,
                          ur::Joints* to_joints) {
  absl::Status status = CheckStraightMove(arm.model, arm.flange_T_tcp, from_joints, from, to,
                                          arm.straight_moves, to_joints);
  if (status.ok() || status.code() != absl::StatusCode::kFailedPrecondition) return status;
  return absl::FailedPreconditionError(absl::StrCat("straight move ", name, " ", status.message()));
}

// The pick half as the controller runs it: I -> M (movej), M -> G, G -> R.
absl::Status SimulatePick(const PickArm& arm, const PlanningScene* scene, PickPlan& plan) {
  plan.initial_joints = arm.joints;
  absl::Status status =
      FreeMove(arm, "M (approach)", plan.approach, plan.initial_joints, &plan.approach_joints);
  if (status.ok() && scene != nullptr) {
    status = CheckFreeMove(arm.model, arm.flange_T_tcp, plan.initial_joints, plan.approach_joints,
                           std::nullopt, *scene, arm.free_moves, "I->M (approach)");
  }
  if (status.ok()) {
    status = StraightMove(arm, "M->G (grasp)", plan.approach, plan.grasp, plan.approach_joints,
                          &plan.grasp_joints);
  }
  if (status.ok()) {
    status = StraightMove(arm, "G->R (retrieve)", plan.grasp, plan.retrieve, plan.grasp_joints,
                          &plan.retrieve_joints);
  }
  return status;
}

// Transit heights above R's tried in turn, m.
constexpr std::array<double, 4> kTransitRaises = {0.0, 0.1, 0.2, 0.3};

// R -> place_above clear of the scene: directly, or through T (see the
// header). Sets place_above_joints, and transit when it takes one.
absl::Status CarryClear(const PickArm& arm, const PlanningScene& scene, const Workspace& workspace,
                        PickPlan& plan) {
  const HeldBox held{plan.box_dims, plan.tcp_T_box};
  absl::Status direct =
      CheckFreeMove(arm.model, arm.flange_T_tcp, plan.retrieve_joints, plan.place_above_joints,
                    held, scene, arm.free_moves, "R->place_above");
  if (direct.ok()) return direct;
  const double base_z =
      std::max(plan.retrieve.translation().z(), plan.place_above.translation().z());
  for (double raise : kTransitRaises) {
    Eigen::Isometry3d transit = plan.place_above;
    transit.translation().z() = base_z + raise;
    if (!workspace.Contains(transit.translation())) break;
    ur::Joints transit_joints{}, place_above_joints{};
    if (!FreeMove(arm, "T (transit)", transit, plan.retrieve_joints, &transit_joints).ok())
      continue;
    if (!CheckFreeMove(arm.model, arm.flange_T_tcp, plan.retrieve_joints, transit_joints, held,
                       scene, arm.free_moves, "R->T")
             .ok()) {
      continue;
    }
    if (!FreeMove(arm, "place_above", plan.place_above, transit_joints, &place_above_joints).ok() ||
        !CheckFreeMove(arm.model, arm.flange_T_tcp, transit_joints, place_above_joints, held, scene,
                       arm.free_moves, "T->place_above")
             .ok()) {
      continue;
    }
    plan.transit = transit;
    plan.transit_joints = transit_joints;
    plan.place_above_joints = place_above_joints;
    return absl::OkStatus();
  }
  return absl::FailedPreconditionError(absl::StrCat(
      direct.message(), ", and no transit above the slot (up to 0.3 m above R) is clear"));
}

// The place half: R -> place_above (movej, through T when needed),
// place_above -> F and back.
absl::Status SimulatePlace(const PickArm& arm, const PlanningScene* scene,
                           const Workspace& workspace, PickPlan& plan) {
  plan.transit.reset();
  absl::Status status = FreeMove(arm, "place_above", plan.place_above, plan.retrieve_joints,
                                 &plan.place_above_joints);
  if (status.ok() && scene != nullptr) status = CarryClear(arm, *scene, workspace, plan);
  if (status.ok()) {
    status = StraightMove(arm, "place_above->F (place)", plan.place_above, plan.place,
                          plan.place_above_joints, &plan.place_joints);
  }
  if (status.ok()) {
    ur::Joints back;
    status = StraightMove(arm, "F->place_above (leave)", plan.place, plan.place_above,
                          plan.place_joints, &back);
  }
  return status;
}

}  // namespace

absl::StatusOr<PickPlan> PlanPick(const PickArm& arm, const BoxInBase& box, const BoxDims& dims,
                                  const Eigen::Isometry3d& base_T_slot, int slot,
                                  const WaypointOptions& waypoints, const Workspace& workspace,
                                  const PlanningScene* scene) {
  const Eigen::Isometry3d initial = TcpPoseFromJoints(arm.model, arm.joints, arm.flange_T_tcp);
  const std::array<Eigen::Isometry3d, 4> grasps =
      GraspCandidates(box, Eigen::Quaterniond(initial.linear()));
  const std::vector<Eigen::Isometry3d> places = PlaceOrientations(box.grasp_face, dims);

  // Positions do not depend on the orientation choice: one workspace check.
  {
    const PickPlan plan =
        Waypoints(initial, box, dims, grasps[0], base_T_slot, places[0], slot, waypoints);
    for (const auto& [name, pose] : Commanded(plan)) {
      if (!workspace.Contains(pose->translation())) {
        return absl::FailedPreconditionError(
            absl::StrFormat("waypoint %s at %s is outside the workspace %s .. %s", name,
                            Xyz(pose->translation()), Xyz(workspace.min_m), Xyz(workspace.max_m)));
      }
    }
  }

  absl::Status first_failure;
  for (const Eigen::Isometry3d& grasp : grasps) {
    // Place orientations by least rotation from this grasp.
    std::vector<PickPlan> candidates;
    for (const Eigen::Isometry3d& slot_T_box : places) {
      candidates.push_back(
          Waypoints(initial, box, dims, grasp, base_T_slot, slot_T_box, slot, waypoints));
    }
    std::stable_sort(candidates.begin(), candidates.end(),
                     [](const PickPlan& a, const PickPlan& b) {
                       return a.place_rotation_rad < b.place_rotation_rad;
                     });
    // The pick half is the same for every place orientation.
    absl::Status status = SimulatePick(arm, scene, candidates.front());
    if (!status.ok()) {
      if (status.code() != absl::StatusCode::kFailedPrecondition) return status;
      if (first_failure.ok()) first_failure = status;
      continue;
    }
    for (PickPlan& plan : candidates) {
      plan.initial_joints = candidates.front().initial_joints;
      plan.approach_joints = candidates.front().approach_joints;
      plan.grasp_joints = candidates.front().grasp_joints;
      plan.retrieve_joints = candidates.front().retrieve_joints;
      status = SimulatePlace(arm, scene, workspace, plan);
      if (status.ok()) return plan;
      if (status.code() != absl::StatusCode::kFailedPrecondition) return status;
      if (first_failure.ok()) first_failure = status;
    }
  }
  return absl::FailedPreconditionError(
      absl::StrCat(first_failure.message(), " (nor with any other tool rotation)"));
}

absl::StatusOr<PickPlan> PlanPickForSlot(const RobotClientOptions& options,
                                         const ur::Joints& current_joints, const BoxInBase& box,
                                         int slot) {
  return PlanPickForSlot(options, current_joints, box, slot, options.perception.box);
}

absl::StatusOr<PickPlan> PlanPickForSlot(const RobotClientOptions& options,
                                         const ur::Joints& current_joints, const BoxInBase& box,
                                         int slot, const BoxDims& dims,
                                         const PlanningScene* scene) {
  absl::StatusOr<Eigen::Isometry3d> base_T_slot = SlotPose(options.place_pattern, slot);
  if (!base_T_slot.ok()) return base_T_slot.status();
  PickArm arm;
  arm.model = options.robot.arm_model;
  arm.flange_T_tcp = options.gripper.flange_T_tcp;
  arm.joints = current_joints;
  arm.branch_reference = options.clear_joints;
  arm.straight_moves.linear_speed_m_s = options.motion.linear_speed_m_s;
  return PlanPick(arm, box, dims, *base_T_slot, slot, options.waypoints, options.workspace, scene);
}

}  // namespace cornerpose::robot_client
