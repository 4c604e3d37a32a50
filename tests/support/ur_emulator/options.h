// Options of the UR controller emulator (tests/support/ur_emulator).
#pragma once

#include <memory>
#include <string>

#include "robot_client/ur/kinematics.h"
#include "robot_client/ur/pose.h"
#include "tests/support/ur_emulator/arm_world.h"

namespace cornerpose::ur_emulator {

struct UrEmulatorOptions {
  // Address the three servers listen on.
  std::string host = "127.0.0.1";
  // TCP ports; 0 lets the OS choose (tests). The real controller's are
  // 29999 / 30001 / 30004, the ur_emulator binary's defaults.
  int dashboard_port = 0;
  int primary_port = 0;
  int rtde_port = 0;

  ur::ArmModel model = ur::ArmModel::kUr5e;
  // Joint angles at start-up, radians: a "home" pose with the flange above
  // the table in front of the base, tool pointing down.
  ur::Joints initial_joints = {0.0, -1.571, 1.571, -1.571, -1.571, 0.0};

  // Simulated seconds per wall-clock second; > 0. Tests use e.g. 20 so a
  // pick finishes in well under a second of wall time.
  double time_scale = 1.0;
  // Control period of the simulation, simulated seconds (125 Hz).
  double control_period_s = 0.008;
  // Joint speed / acceleration caps applied on top of a move's v and a,
  // rad/s and rad/s^2 (UR5e limits, ur-interface.md section 4).
  double max_joint_speed = 3.14159265358979323846;
  double max_joint_accel = 40.0;
  // Cartesian caps for movel, m/s and m/s^2.
  double max_tool_speed = 3.0;
  double max_tool_accel = 15.0;
  // A movel step whose IK solution jumps by more than this on any joint is a
  // singularity / branch flip: the move fails. Radians per control period.
  double max_joint_step_rad = 0.25;

  // Start in POWER_OFF (the daemon has to power on and release the brakes
  // through the dashboard); false starts powered with brakes released
  // (RUNNING).
  bool start_powered_off = true;
  // Simulated seconds from `power on` to IDLE and from `brake release` to
  // RUNNING.
  double power_on_delay_s = 0.5;
  double brake_release_delay_s = 0.5;
  // Simulated seconds after a protective stop before `unlock protective
  // stop` is accepted (the real controller: 5 s).
  double protective_stop_unlock_delay_s = 5.0;

  // Rate of ROBOT_STATE packages on the primary port, wall Hz.
  double primary_state_hz = 10.0;
  // RTDE: highest output frequency accepted, wall Hz (e-Series: 500).
  double rtde_max_frequency_hz = 500.0;
  // Controller software version reported on every interface.
  int version_major = 5;
  int version_minor = 11;
  int version_bugfix = 1;
  int version_build = 108318;

  // The simulated cell the arm acts on (suction, carried boxes, collisions);
  // null: free space. Shared so a test can keep reading it.
  std::shared_ptr<ArmWorld> world;
};

}  // namespace cornerpose::ur_emulator
