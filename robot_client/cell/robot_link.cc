#include "robot_client/cell/robot_link.h"

#include <utility>

#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"
#include "robot_client/ur/dashboard.h"

namespace cornerpose::robot_client {

RobotLink::RobotLink(RobotConnectionOptions options)
    : options_(std::move(options)),
      dashboard_(std::make_unique<ur::DashboardClient>()),
      primary_(std::make_unique<ur::PrimaryClient>()),
      rtde_(std::make_unique<ur::RtdeClient>(
          ur::RtdeClientOptions{.frequency = options_.rtde_frequency_hz})) {}

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
                                         absl::Duration timeout) {
  if (absl::Status s = primary_->SendScript(text); !s.ok()) {
    return ur::ProgramOutcome{.kind = ur::ProgramOutcome::kConnectionLost,
                              .detail = std::string(s.message())};
  }
  return primary_->WaitForProgram(name, timeout);
}

}  // namespace cornerpose::robot_client
