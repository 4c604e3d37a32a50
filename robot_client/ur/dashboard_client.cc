#include "robot_client/ur/dashboard_client.h"

#include <thread>

#include "absl/strings/ascii.h"
#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"

namespace cornerpose::ur {

DashboardClient::DashboardClient(DashboardOptions options) : options_(options) {}

DashboardClient::~DashboardClient() { Close(); }

absl::Status DashboardClient::Connect(absl::string_view host, int port, absl::Duration timeout) {
  const absl::Time deadline = absl::Now() + timeout;
  absl::StatusOr<TcpConnection> connection = TcpConnection::Connect(host, port, timeout);
  if (!connection.ok()) return connection.status();
  absl::StatusOr<std::string> banner = connection->ReadLine(deadline - absl::Now());
  if (!banner.ok()) {
    return absl::Status(banner.status().code(),
                        absl::StrCat("dashboard banner: ", banner.status().message()));
  }
  if (!absl::StrContains(absl::AsciiStrToLower(*banner), "dashboard server")) {
    return absl::FailedPreconditionError(
        absl::StrCat("not a UR dashboard server at ", host, ":", port, ": '", *banner, "'"));
  }
  std::lock_guard<std::mutex> lock(mutex_);
  connection_ = std::move(*connection);
  return absl::OkStatus();
}

bool DashboardClient::connected() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return connection_.valid();
}

void DashboardClient::Close() {
  std::lock_guard<std::mutex> lock(mutex_);
  connection_.Close();
}

absl::StatusOr<std::string> DashboardClient::Command(absl::string_view line,
                                                     absl::Duration timeout) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!connection_.valid()) return absl::UnavailableError("dashboard: not connected");
  const absl::Time deadline = absl::Now() + timeout;
  absl::Status written = connection_.WriteAll(absl::StrCat(line, "\n"), timeout);
  absl::StatusOr<std::string> reply =
      written.ok() ? connection_.ReadLine(deadline - absl::Now()) : written;
  if (!reply.ok()) {
    // A reply that did not come in time would answer the next command;
    // the connection cannot be trusted any more.
    connection_.Close();
    return absl::Status(reply.status().code(),
                        absl::StrCat("dashboard '", line, "': ", reply.status().message()));
  }
  return reply;
}

absl::StatusOr<ur::RobotMode> DashboardClient::RobotMode(absl::Duration timeout) {
  absl::StatusOr<std::string> reply = Command("robotmode", timeout);
  if (!reply.ok()) return reply.status();
  return ParseRobotModeReply(*reply);
}

absl::StatusOr<ur::SafetyMode> DashboardClient::SafetyStatus(absl::Duration timeout) {
  const absl::Time deadline = absl::Now() + timeout;
  absl::StatusOr<std::string> reply = Command("safetystatus", timeout);
  if (!reply.ok()) return reply.status();
  absl::StatusOr<ur::SafetyMode> mode = ParseSafetyReply(*reply);
  if (mode.ok()) return mode;
  reply = Command("safetymode", deadline - absl::Now());
  if (!reply.ok()) return reply.status();
  return ParseSafetyReply(*reply);
}

absl::StatusOr<bool> DashboardClient::ProgramRunning(absl::Duration timeout) {
  absl::StatusOr<std::string> reply = Command("running", timeout);
  if (!reply.ok()) return reply.status();
  return ParseRunningReply(*reply);
}

absl::Status DashboardClient::Expect(absl::string_view command, absl::string_view reply_prefix,
                                     absl::Duration timeout) {
  absl::StatusOr<std::string> reply = Command(command, timeout);
  if (!reply.ok()) return reply.status();
  if (!absl::StartsWithIgnoreCase(*reply, reply_prefix)) {
    return absl::FailedPreconditionError(
        absl::StrCat("dashboard '", command, "' refused: '", *reply, "'"));
  }
  return absl::OkStatus();
}

absl::Status DashboardClient::PowerOn(absl::Duration timeout) {
  return Expect("power on", "Powering on", timeout);
}
absl::Status DashboardClient::BrakeRelease(absl::Duration timeout) {
  return Expect("brake release", "Brake releasing", timeout);
}
absl::Status DashboardClient::UnlockProtectiveStop(absl::Duration timeout) {
  return Expect("unlock protective stop", "Protective stop releasing", timeout);
}
absl::Status DashboardClient::Stop(absl::Duration timeout) {
  return Expect("stop", "Stopped", timeout);
}

absl::Status DashboardClient::WaitForMode(std::initializer_list<ur::RobotMode> wanted,
                                          absl::Time deadline) {
  std::string last = "none";
  while (true) {
    const absl::Duration left = deadline - absl::Now();
    if (left <= absl::ZeroDuration()) break;
    absl::StatusOr<ur::RobotMode> mode = RobotMode(left);
    if (!mode.ok()) {
      if (!absl::IsInvalidArgument(mode.status())) return mode.status();
      last = std::string(mode.status().message());
    } else {
      for (ur::RobotMode w : wanted) {
        if (*mode == w) return absl::OkStatus();
      }
      last = RobotModeName(*mode);
    }
    std::this_thread::sleep_for(absl::ToChronoNanoseconds(
        std::min(options_.poll_interval, std::max(deadline - absl::Now(), absl::ZeroDuration()))));
  }
  std::vector<std::string> names;
  for (ur::RobotMode w : wanted) names.push_back(RobotModeName(w));
  return absl::DeadlineExceededError(absl::StrCat(
      "robot mode did not reach ", absl::StrJoin(names, " or "), "; last seen: ", last));
}

absl::Status DashboardClient::BringUp(absl::Duration timeout) {
  const absl::Time deadline = absl::Now() + timeout;
  absl::StatusOr<ur::RobotMode> mode = RobotMode(timeout);
  if (!mode.ok()) return mode.status();
  if (*mode == ur::RobotMode::kRunning) return absl::OkStatus();
  if (*mode != ur::RobotMode::kIdle) {
    if (absl::Status s = PowerOn(deadline - absl::Now()); !s.ok()) return s;
    if (absl::Status s = WaitForMode({ur::RobotMode::kIdle, ur::RobotMode::kRunning}, deadline);
        !s.ok()) {
      return s;
    }
  }
  if (absl::Status s = BrakeRelease(deadline - absl::Now()); !s.ok()) return s;
  return WaitForMode({ur::RobotMode::kRunning}, deadline);
}

}  // namespace cornerpose::ur
