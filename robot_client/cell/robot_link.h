// The daemon's three connections to the UR controller, as one link: the
// dashboard server (modes, bring-up), the primary interface (programs in,
// their STARTED/STOPPED and exceptions out) and RTDE (joint state, TCP pose,
// safety and robot mode at the configured rate). See ur-interface.md.
#pragma once

#include <functional>
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

  // The newest RTDE state; UNAVAILABLE when not connected,
  // DEADLINE_EXCEEDED when older than rtde_max_age_s (a stalled stream).
  absl::StatusOr<ur::RtdeState> State() const;

  // Why the link cannot be trusted now (a connection down, RTDE stale);
  // nullopt when it can. The check before planning and sending a program.
  std::optional<std::string> Unhealthy() const;

  // Why the link is lost (a connection down, or RTDE silent or stale for
  // read_timeout_s); nullopt when it is not. The watchdog while a program
  // runs: the program runs on the controller, and a state a few packages
  // late (a busy host) must not make its end unknown; a stream that stays
  // quiet still stops it within read_timeout_s.
  std::optional<std::string> Lost() const;

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
  // Completed only on the program's own done message (`<name>: done`);
  // `cancel` is polled while it runs (see ur::ProgramWait).
  ur::ProgramOutcome RunProgram(absl::string_view name, absl::string_view text,
                                absl::Duration timeout,
                                std::function<std::optional<std::string>()> cancel = {});

  // Stops whatever program runs (dashboard `stop`) and waits, within
  // stop_confirm_timeout_s, for a fresh RTDE state received after the stop
  // that says no program runs (runtime state STOPPED, program-running bit
  // clear). OK only then; the reason otherwise.
  absl::Status StopProgramAndConfirm();

 private:
  // A connection down, or no RTDE state newer than `max_rtde_age`.
  std::optional<std::string> Problem(absl::Duration max_rtde_age) const;

  const RobotConnectionOptions options_;
  std::unique_ptr<ur::DashboardClient> dashboard_;
  std::unique_ptr<ur::PrimaryClient> primary_;
  std::unique_ptr<ur::RtdeClient> rtde_;
};

}  // namespace cornerpose::robot_client
