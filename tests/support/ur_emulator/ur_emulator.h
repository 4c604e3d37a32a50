// An emulator of a UR controller (UR5 / UR5e) for the daemon's tests and the
// demo cell: the dashboard server (29999), the primary client interface
// (30001, script in; state, KEY / TEXT / RUNTIME_EXCEPTION / SAFETY_MODE out)
// and RTDE (30004), over a simulated arm that executes the URScript subset
// the daemon emits (urscript.h) with the same kinematics as the daemon, and
// records every program and step it ran. Wire formats: robot_client/ur.
//
// Emulator choices where the real controller is not documented (see
// shared/design/ur-interface.md): a program sent while the robot is not
// RUNNING or not in NORMAL safety mode is not started and answered with a
// RUNTIME_EXCEPTION (line 0, column 0); a script that does not compile
// does not stop the running program; blends (r > 0) stop at the waypoint;
// `sec` programs run like `def` ones; socket_* functions, set_payload and
// stopl/stopj are recorded but do nothing (no socket is opened); tool
// digital outputs are bits 16-17 of the primary and RTDE output words.
#pragma once

#include <functional>
#include <memory>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/time/time.h"
#include "tests/support/ur_emulator/controller.h"
#include "tests/support/ur_emulator/options.h"

namespace cornerpose::ur_emulator {

class Servers;

class UrEmulator {
 public:
  // Starts the controller and listens on the three ports. Fails (e.g. a
  // port in use, time_scale <= 0) with the reason.
  static absl::StatusOr<std::unique_ptr<UrEmulator>> Start(UrEmulatorOptions options);
  // Closes every connection and stops.
  ~UrEmulator();
  UrEmulator(const UrEmulator&) = delete;
  UrEmulator& operator=(const UrEmulator&) = delete;

  // The ports actually bound (the OS's choice where the option was 0).
  int dashboard_port() const;
  int primary_port() const;
  int rtde_port() const;
  const UrEmulatorOptions& options() const { return controller_->options(); }

  // Fault injection. TriggerProtectiveStop: as a protective stop on the
  // arm (see Controller::TriggerProtectiveStop). DropConnections: closes
  // every client socket on all three ports; new connections are accepted.
  void TriggerProtectiveStop() { controller_->TriggerProtectiveStop(); }
  void DropConnections();
  // More faults: every link open but silent (see Servers::SetSilent); the
  // RTDE stream stalled; programs that never end; emergency stop and its
  // reset (see Controller). Each holds until called again with false.
  void SetLinksSilent(bool silent);
  void SetRtdeStalled(bool stalled);
  void SetHangPrograms(bool hang) { controller_->SetHangPrograms(hang); }
  void TriggerEmergencyStop() { controller_->TriggerEmergencyStop(); }
  void ResetEmergencyStop() { controller_->ResetEmergencyStop(); }

  // State, thread-safe.
  RobotSnapshot Snapshot() const { return controller_->Snapshot(); }
  std::vector<ExecutedProgram> Programs() const { return controller_->Programs(); }
  // Waits (wall time) until `predicate` holds on the state; see
  // Controller::WaitFor.
  bool WaitFor(const std::function<bool(const RobotSnapshot&)>& predicate,
               absl::Duration timeout) const {
    return controller_->WaitFor(predicate, timeout);
  }
  // Waits until `count` programs have ended (any outcome).
  bool WaitForProgramsFinished(size_t count, absl::Duration timeout) const;

  // The simulated controller, for the control words tests want to drive
  // directly (PowerOn, SubmitScript, ...).
  Controller& controller() { return *controller_; }

 private:
  UrEmulator() = default;

  std::unique_ptr<Controller> controller_;
  std::unique_ptr<Servers> servers_;
};

}  // namespace cornerpose::ur_emulator
