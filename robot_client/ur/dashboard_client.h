// Client for the dashboard server (port 29999): one command line, one reply
// line. Used for bring-up (power on, brake release) and recovery (unlock
// protective stop, stop).
#pragma once

#include <mutex>
#include <string>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "absl/time/time.h"
#include "robot_client/ur/dashboard.h"
#include "robot_client/ur/tcp.h"

namespace cornerpose::ur {

struct DashboardOptions {
  // How often BringUp polls `robotmode`.
  absl::Duration poll_interval = absl::Milliseconds(100);
};

// Thread-safe: commands are serialised (the protocol is strictly
// request/reply on one socket).
class DashboardClient {
 public:
  explicit DashboardClient(DashboardOptions options = {});
  ~DashboardClient();

  DashboardClient(const DashboardClient&) = delete;
  DashboardClient& operator=(const DashboardClient&) = delete;

  // Connects and reads the "Connected: Universal Robots Dashboard Server"
  // banner (FAILED_PRECONDITION for another banner). Replaces an earlier
  // connection.
  absl::Status Connect(absl::string_view host, int port = 29999,
                       absl::Duration timeout = absl::Seconds(5));
  bool connected() const;
  void Close();

  // Sends `line` (a "\n" is added) and returns the reply line. A failed
  // socket marks the client disconnected.
  absl::StatusOr<std::string> Command(absl::string_view line,
                                      absl::Duration timeout = absl::Seconds(5));

  absl::StatusOr<ur::RobotMode> RobotMode(absl::Duration timeout = absl::Seconds(5));
  // `safetystatus` (e-Series 5.4+), falling back to `safetymode` when the
  // controller does not understand it.
  absl::StatusOr<ur::SafetyMode> SafetyStatus(absl::Duration timeout = absl::Seconds(5));
  // `running`.
  absl::StatusOr<bool> ProgramRunning(absl::Duration timeout = absl::Seconds(5));

  // Each sends the command and checks the success reply ("Powering on",
  // "Brake releasing", "Protective stop releasing", "Stopped");
  // FAILED_PRECONDITION with the controller's reply otherwise.
  absl::Status PowerOn(absl::Duration timeout = absl::Seconds(5));
  absl::Status BrakeRelease(absl::Duration timeout = absl::Seconds(5));
  absl::Status UnlockProtectiveStop(absl::Duration timeout = absl::Seconds(5));
  absl::Status Stop(absl::Duration timeout = absl::Seconds(5));

  // Power on (unless already IDLE / RUNNING), wait for IDLE, brake release,
  // wait for RUNNING, all within `timeout`. DEADLINE_EXCEEDED names the last
  // robot mode seen.
  absl::Status BringUp(absl::Duration timeout = absl::Seconds(30));

 private:
  absl::Status Expect(absl::string_view command, absl::string_view reply_prefix,
                      absl::Duration timeout);
  // Polls robotmode until one of `wanted` or the deadline.
  absl::Status WaitForMode(std::initializer_list<ur::RobotMode> wanted, absl::Time deadline);

  const DashboardOptions options_;
  mutable std::mutex mutex_;
  TcpConnection connection_;  // guarded by mutex_
};

}  // namespace cornerpose::ur
