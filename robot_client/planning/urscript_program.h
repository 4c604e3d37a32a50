// The URScript program of one pick, rendered from one template (see
// kPickProgramTemplate in urscript_program.cc and ur-interface.md section 3).
//
// The program, statement by statement (every move blocks: no blending):
//
//   def <name>():
//     set_tcp(<tcp_offset>)              the suction cup tip, flange frame
//     textmsg("<name>: start")
//     movej(<M joints>, a=<ja>, v=<jv>)   approach I -> M, free move in joint
//                                         space to the planned IK solution
//     movel(<G>, a=<la>, v=<lv>)          grasp, straight down onto the face
//     <suction>(<index>, True)            vacuum on
//     sleep(<grasp_settle_s>)
//     movel(<R>, a=<la>, v=<lv>)          retrieve, straight up
//     movej(<place_above joints>, a=<ja>, v=<jv>)
//     movel(<F>, a=<la>, v=<lv>)          lower onto the slot
//     <suction>(<index>, False)           vacuum off
//     sleep(<release_s>)
//     movel(<place_above>, a=<la>, v=<lv>)
//     movej(<clear_joints>, a=<ja>, v=<jv>)   out of the camera's view
//     textmsg("<name>: done")
//   end
//
// Poses are TCP poses in the base frame as literals p[x, y, z, rx, ry, rz]
// (metres, rotation vector in radians; ur::FormatPoseLiteral); the free-move
// targets (PickPlan::approach_joints, place_above_joints: the planner's
// choice of configuration branch) and the clear pose are joint vectors
// [q1, ..., q6] in radians. <suction> is
// set_tool_digital_out or set_standard_digital_out. Numbers are plain
// decimals (no exponent). The text is ASCII, two-space indented, `def` and
// `end` in column 1, ending in a newline.
#pragma once

#include <string>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "robot_client/config/robot_config.h"
#include "robot_client/planning/pick_plan.h"
#include "robot_client/ur/pose.h"

namespace cornerpose::robot_client {

// OK when `name` is a URScript program name this daemon emits: matches
// ^[A-Za-z_][A-Za-z0-9_]*$ and has at most 31 characters; INVALID_ARGUMENT
// saying which rule it breaks otherwise.
absl::Status ValidateProgramName(absl::string_view name);

// "pick_<n>" with n zero-padded to 4 digits ("pick_0007"); n >= 0.
std::string PickProgramName(int pick_number);

// The program for `plan` (see above), with the gripper's TCP offset, suction
// output and waits, the motion's speeds and accelerations, and the clear
// joints. INVALID_ARGUMENT for a bad name (ValidateProgramName) or a
// non-finite pose, joint or number.
absl::StatusOr<std::string> RenderPickProgram(absl::string_view name, const PickPlan& plan,
                                              const GripperOptions& gripper,
                                              const MotionOptions& motion,
                                              const ur::Joints& clear_joints);

}  // namespace cornerpose::robot_client
