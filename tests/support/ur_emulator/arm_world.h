// What the emulated arm acts on: an optional world (tests/support/cell_sim)
// that the controller tells about every control step and output change, so
// a suction cup can grip boxes, carry them and set them down, and contact
// between the arm and the world raises a protective stop as on a real arm.
// Without one the emulator moves in free space, as before.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <optional>
#include <string>

#include "robot_client/ur/kinematics.h"

namespace cornerpose::ur_emulator {

// The arm after a control step (or an output change).
struct ArmState {
  double time_s = 0.0;  // simulated seconds since the controller started
  ur::Joints joints{};
  Eigen::Isometry3d base_T_tcp = Eigen::Isometry3d::Identity();  // FK * the TCP offset in force
  Eigen::Isometry3d flange_T_tcp = Eigen::Isometry3d::Identity();
  uint32_t tool_outputs = 0;      // bit n = tool digital output n
  uint32_t standard_outputs = 0;  // bit n = standard digital output n
  std::string program;            // the running program's name; empty when none runs
};

class ArmWorld {
 public:
  virtual ~ArmWorld() = default;

  // After every control step of a move, with the new joints. A returned text
  // (what touched what) makes the controller stop the arm there with a
  // protective stop, as a real arm's collision detection does. Called with
  // the controller's lock held: must not call back into the controller.
  virtual std::optional<std::string> OnStep(const ArmState& state) = 0;

  // After any digital output changed (suction on / off), same lock rule.
  virtual void OnOutputs(const ArmState& state) = 0;

  // A program started running (same lock rule).
  virtual void OnProgramStart(const std::string& program, double time_s) = 0;

  // A program ended (any outcome) at simulated time_s; called without the
  // controller's lock,
  // before PROGRAM_STOPPED is reported, so the world can bring what its
  // camera shows up to date first (a client that waits for the program's
  // end and then for a new frame never sees the scene as it was before).
  virtual void OnProgramEnd(const std::string& program, bool completed, double time_s) = 0;
};

}  // namespace cornerpose::ur_emulator
