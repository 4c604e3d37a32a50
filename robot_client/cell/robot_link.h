// The daemon's three connections to the UR controller, as one link: the
// dashboard server (modes, bring-up), the primary interface (programs in,
// their STARTED/STOPPED and exceptions out) and RTDE (joint state, TCP pose,
// safety and robot mode at the configured rate). See ur-interface.md.
#pragma once

#include <memory>
#include <optional>
#include <string>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "absl/time/time.h"
#include "robot_client/config/robot_config.h"
#include "robot_client/ur/dashboard_client.h"
#include "robot_client/ur/primary_client.h"
#include "robot_client/ur/rtde_client.h"

namespace cornerpose::robot_client {

class RobotLink {
 public:
  explicit RobotLink(RobotConnectionOptions options);

  // Opens all three connections (each within the connect timeout); on a
  // failure closes them all and says which one failed.
  absl::Status Connect();
  // True while all three are connected.
  bool connected() const;
  void Close();

  // The newest RTDE state; UNAVAILABLE when not connected.
  absl::StatusOr<ur::RtdeState> State() const;

  // Why the arm cannot move now: a protective, safeguard or emergency stop,
  // or a safety fault (from the RTDE safety mode); nullopt when the safety
  // mode is NORMAL or REDUCED.
  std::optional<std::string> SafetyStop() const;

  // Waits up to `timeout` for the RTDE state to report a safety stop (after
  // the primary interface said a program ended in one: the two streams are
  // not ordered). True once it does.
  bool WaitForSafetyStop(absl::Duration timeout) const;

  // Powers the arm on and releases the brakes unless it is RUNNING.
  absl::Status BringUp(absl::Duration timeout);

  // Sends the program and follows it to its end on the primary interface.
  ur::ProgramOutcome RunProgram(absl::string_view name, absl::string_view text,
                                absl::Duration timeout);

 private:
  const RobotConnectionOptions options_;
  std::unique_ptr<ur::DashboardClient> dashboard_;
  std::unique_ptr<ur::PrimaryClient> primary_;
  std::unique_ptr<ur::RtdeClient> rtde_;
};

}  // namespace cornerpose::robot_client
