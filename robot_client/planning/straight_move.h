// Whether the controller can run a straight TCP move (URScript movel) from a
// known joint state: the line is followed the way the controller follows it,
// position interpolated linearly and rotation by slerp, each sample's
// inverse kinematics taken nearest the previous sample's joints. A move is
// refused when a sample has no solution (it leaves the arm's reach) or when
// a joint would have to turn faster than the arm allows at the move's speed:
// near a singularity (wrist, elbow stretched, wrist over the base axis) or at
// an IK branch flip the joint speed for a given tool speed grows without
// bound, and the controller faults (protective stop; the emulator's
// runtime_error_movel_joint_jump).
//
// The rule, per sample: a sample that moves the tool by ds metres and turns
// it by dtheta radians takes at least t = max(ds / linear_speed,
// dtheta / angular_speed) seconds, so no joint may change by more than
// max_joint_speed * t. With the defaults (0.1 m/s, pi/2 rad/s) that is 15.7
// rad per metre of tool travel, 0.031 rad per 2 mm sample: twenty times
// stricter than the emulator's jump bound (0.25 rad per 8 ms control step,
// 0.8 mm at 0.1 m/s, i.e. 312 rad/m) and half the UR5e's joint speed limit
// (pi rad/s), the margin for the accelerating parts of a move and the
// controller's own singularity guard. Approaching a singularity the needed
// joint speed grows steeply, so the margin costs little reach: in the demo
// cell pi and pi/2 refuse the same picks.
#pragma once

#include <Eigen/Geometry>

#include "absl/status/status.h"
#include "robot_client/ur/kinematics.h"
#include "robot_client/ur/pose.h"

namespace cornerpose::robot_client {

struct StraightMoveOptions {
  // Sample spacing: at most this far along the line, metres, and this much
  // tool rotation, radians; both > 0.
  double step_m = 0.002;
  double step_rad = 0.005;
  // The move's tool speed (MotionOptions::linear_speed_m_s), m/s; > 0.
  double linear_speed_m_s = 0.1;
  // The tool's rotation speed during movel (the controller's default, as
  // the emulator uses), rad/s; > 0.
  double angular_speed_rad_s = 1.05;
  // Fastest joint speed a move may need, rad/s; > 0. Half the UR5e's
  // pi rad/s (see above).
  double max_joint_speed_rad_s = 0.5 * 3.14159265358979323846;
};

// Follows the straight TCP move from_tcp -> to_tcp (base_T_tcp poses) of arm
// `model` with the TCP at flange_T_tcp, starting at start_joints (whose TCP
// must be from_tcp: INVALID_ARGUMENT otherwise, or for bad options). OK with
// *end_joints (may be null) = the joints at to_tcp; FAILED_PRECONDITION
// naming where otherwise, e.g. "passes a singularity at (0.000, -0.322,
// 0.676): joint 3 would turn 0.212 rad in 2.0 mm (max 0.031)" or "leaves the
// arm's reach at (...)".
absl::Status CheckStraightMove(ur::ArmModel model, const Eigen::Isometry3d& flange_T_tcp,
                               const ur::Joints& start_joints, const Eigen::Isometry3d& from_tcp,
                               const Eigen::Isometry3d& to_tcp, const StraightMoveOptions& options,
                               ur::Joints* end_joints);

}  // namespace cornerpose::robot_client
