#include "robot_client/cell/robot_link.h"

#include <utility>

#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"
#include "robot_client/ur/dashboard.h"

namespace cornerpose::robot_client {

RobotLink::RobotLink(RobotConnectionOptions options)
    : options_(std::move(options)),
      dashboard_(std::make_unique<ur::DashboardClient>()),
      primary_(std::make_unique<ur::PrimaryClient>(
          ur::PrimaryClientOptions{.read_timeout = absl::Seconds(options_.read_timeout_s)})),
      rtde_(std::make_unique<ur::RtdeClient>(
          ur::RtdeClientOptions{.frequency = options_.rtde_frequency_hz,
                                .read_timeout = absl::Seconds(options_.read_timeout_s),
                                .max_age = absl::Seconds(options_.rtde_max_age_s)})) {}

absl::Status RobotLink::Connect() {
  const absl::Duration timeout = absl::Seconds(options_.connect_timeout_s);
  const std::string& host = options_.host;
  absl::Status s = dashboard_->Connect(host, options_.dashboard_port, timeout);
  if (s.ok()) {
    s = primary_->Connect(host, options_.primary_port, timeout);
    if (!s.ok()) s = absl::Status(s.code(), absl::StrCat("primary interface: ", s.message()));
  } else {
    s = absl::Status(s.code(), absl::StrCat("dashboard server: ", s.message()));
  }
  if (s.ok()) {
    s = rtde_->Connect(host, options_.rtde_port, timeout);
    if (!s.ok()) s = absl::Status(s.code(), absl::StrCat("RTDE: ", s.message()));
  }
  if (!s.ok()) Close();
  return s;
}

bool RobotLink::connected() const {
  return dashboard_->connected() && primary_->connected() && rtde_->connected();
}

void RobotLink::Close() {
  dashboard_->Close();
  primary_->Close();
  rtde_->Close();
}

absl::StatusOr<ur::RtdeState> RobotLink::State() const { return rtde_->Latest(); }

std::optional<std::string> RobotLink::Unhealthy() const {
  return Problem(absl::Seconds(options_.rtde_max_age_s));
}

std::optional<std::string> RobotLink::Lost() const {
  return Problem(absl::Seconds(options_.read_timeout_s));
}

std::optional<std::string> RobotLink::Problem(absl::Duration max_rtde_age) const {
  if (!dashboard_->connected()) return "dashboard server connection lost";
  if (!primary_->connected()) {
    return absl::StrCat("primary interface lost: ", primary_->connection_status().message());
  }
  absl::StatusOr<ur::RtdeState> state = rtde_->Latest(max_rtde_age);
  if (!state.ok()) return std::string(state.status().message());
  return std::nullopt;
}

absl::Status RobotLink::StopProgramAndConfirm() {
  const absl::Time deadline = absl::Now() + absl::Seconds(options_.stop_confirm_timeout_s);
  const absl::Time stop_sent = absl::Now();
  // "Failed to execute: stop" means no program was running: fine, the
  // RTDE check below is what counts.
  absl::Status stop = dashboard_->Stop(absl::Seconds(options_.stop_confirm_timeout_s));
  if (!stop.ok() && !absl::IsFailedPrecondition(stop)) {
    return absl::Status(stop.code(), absl::StrCat("dashboard stop failed: ", stop.message()));
  }
  // Bit 1 of robot_status_bits: a program runs; runtime_state 1: stopped.
  constexpr uint32_t kProgramRunningBit = 1u << 1;
  constexpr uint32_t kRuntimeStopped = 1;
  absl::StatusOr<ur::RtdeState> state = rtde_->Latest();
  uint64_t sequence = state.ok() ? state->sequence : 0;
  std::string last = state.ok() ? "no state after the stop" : std::string(state.status().message());
  while (absl::Now() < deadline) {
    state = rtde_->WaitForNewer(sequence, deadline - absl::Now());
    if (!state.ok()) {
      last = std::string(state.status().message());
      if (!absl::IsDeadlineExceeded(state.status())) break;
      continue;
    }
    sequence = state->sequence;
    if (state->received < stop_sent) continue;
    if (state->runtime_state == kRuntimeStopped &&
        (state->robot_status_bits & kProgramRunningBit) == 0) {
      return absl::OkStatus();
    }
    last = absl::StrCat("runtime state ", state->runtime_state, ", program still running");
  }
  return absl::DeadlineExceededError(absl::StrCat("cannot confirm the program stopped: ", last));
}

std::optional<std::string> RobotLink::SafetyStop() const {
  absl::StatusOr<ur::RtdeState> state = rtde_->Latest();
  if (!state.ok()) return std::nullopt;
  const auto mode = static_cast<ur::SafetyMode>(state->safety_mode);
  if (mode == ur::SafetyMode::kNormal || mode == ur::SafetyMode::kReduced) return std::nullopt;
  return absl::StrCat("safety mode ", ur::SafetyModeName(mode));
}

bool RobotLink::WaitForSafetyStop(absl::Duration timeout) const {
  const absl::Time deadline = absl::Now() + timeout;
  absl::StatusOr<ur::RtdeState> state = rtde_->Latest();
  while (state.ok()) {
    if (SafetyStop()) return true;
    const absl::Duration left = deadline - absl::Now();
    if (left <= absl::ZeroDuration()) break;
    state = rtde_->WaitForNewer(state->sequence, left);
  }
  return SafetyStop().has_value();
}

absl::Status RobotLink::BringUp(absl::Duration timeout) {
  absl::StatusOr<ur::RtdeState> state = rtde_->Latest();
  if (state.ok() && static_cast<ur::RobotMode>(state->robot_mode) == ur::RobotMode::kRunning) {
    return absl::OkStatus();
  }
  return dashboard_->BringUp(timeout);
}

ur::ProgramOutcome RobotLink::RunProgram(absl::string_view name, absl::string_view text,
                                         absl::Duration timeout,
                                         std::function<std::optional<std::string>()> cancel) {
  if (absl::Status s = primary_->SendScript(text); !s.ok()) {
    ur::ProgramOutcome lost;
    lost.kind = ur::ProgramOutcome::kConnectionLost;
    lost.detail = std::string(s.message());
    return lost;
  }
  ur::ProgramWait wait;
  wait.timeout = timeout;
  wait.done_text = absl::StrCat(name, ": done");
  wait.cancel = std::move(cancel);
  return primary_->WaitForProgram(name, wait);
}

}  // namespace cornerpose::robot_client
