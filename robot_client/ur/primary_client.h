// Client for the primary interface (port 30001): sends URScript programs and
// follows their execution through the robot messages only this port carries
// (KEY PROGRAM_XXX_STARTED / _STOPPED, RUNTIME_EXCEPTION, SAFETY_MODE) and
// the ROBOT_MODE_DATA flags in the 10 Hz state.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "absl/status/status.h"
#include "absl/strings/string_view.h"
#include "absl/time/time.h"
#include "robot_client/ur/primary.h"
#include "robot_client/ur/tcp.h"

namespace cornerpose::ur {

struct ProgramOutcome {
  enum Kind {
    kCompleted,
    kRuntimeException,
    kProtectiveStop,
    kConnectionLost,
    kTimeout,
    // PROGRAM_XXX_STOPPED without the program's own done message (stopped
    // from outside, or cut short): where the arm and the box are is unknown.
    kUnfinished,
    // The caller's cancel check asked to stop waiting (the program may still
    // run: the caller stops it).
    kCancelled,
  };
  Kind kind = kTimeout;
  // What happened, for logs: the exception text with line/column, the
  // safety mode, the socket error.
  std::string detail;
  // Whether PROGRAM_XXX_STARTED was seen for the program.
  bool started = false;
  // TEXT messages (textmsg output) received while waiting, in order.
  std::vector<std::string> text_messages;
};
const char* ProgramOutcomeName(ProgramOutcome::Kind kind);

struct PrimaryClientOptions {
  // A connection that sends nothing for this long is taken as lost (the
  // controller sends ROBOT_STATE at 10 Hz, so a silent half-open link shows
  // within a second). Infinite: never.
  absl::Duration read_timeout = absl::InfiniteDuration();
};

// How WaitForProgram decides the program ended well, and when to give up.
struct ProgramWait {
  absl::Duration timeout = absl::Seconds(120);
  // When set, PROGRAM_XXX_STOPPED counts as completed only after a TEXT
  // message equal to this (the program's last `textmsg`); otherwise it is
  // kUnfinished.
  std::string done_text;
  // Called about every `cancel_poll` while waiting; a returned reason ends
  // the wait with kCancelled and that reason as the detail.
  std::function<std::optional<std::string>()> cancel;
  absl::Duration cancel_poll = absl::Milliseconds(20);
};

// Thread-safe. Owns a reader thread from Connect until Close / destruction.
class PrimaryClient {
 public:
  // Robot messages kept for WaitForProgram; older ones are dropped.
  static constexpr size_t kMaxQueuedMessages = 1000;

  explicit PrimaryClient(PrimaryClientOptions options = {});
  ~PrimaryClient();

  PrimaryClient(const PrimaryClient&) = delete;
  PrimaryClient& operator=(const PrimaryClient&) = delete;

  // Connects and starts the reader. Replaces an earlier connection.
  absl::Status Connect(absl::string_view host, int port = 30001,
                       absl::Duration timeout = absl::Seconds(5));
  bool connected() const;
  void Close();

  // Sends a program (or a control line such as "power on"); a trailing
  // "\n" is added when missing (the controller ignores a last line without
  // one). Clears the queued robot messages first, so WaitForProgram sees
  // only what follows this script.
  absl::Status SendScript(absl::string_view script);

  // Follows the program `name` (the `def name():`) until it stops:
  // kCompleted on PROGRAM_XXX_STOPPED with text == name; kRuntimeException
  // on a RUNTIME_EXCEPTION (or an ERROR_CODE at FAULT level or above);
  // kProtectiveStop on a SAFETY_MODE message other than NORMAL / REDUCED or
  // a ROBOT_MODE_DATA received after the last SendScript with the
  // protective- or emergency-stopped flag; kConnectionLost; kTimeout.
  ProgramOutcome WaitForProgram(absl::string_view name, absl::Duration timeout);
  // The same with a done message and a cancel check (see ProgramWait).
  ProgramOutcome WaitForProgram(absl::string_view name, const ProgramWait& wait);

  // The most recent ROBOT_STATE (sub-packages merged: a field stays until a
  // newer package carries it); nullopt before the first.
  std::optional<RobotState> LatestState() const;
  // Counts ROBOT_STATE packages received.
  uint64_t state_count() const;
  // Waits for a ROBOT_STATE newer than `count`; false on timeout or when the
  // connection is lost.
  bool WaitForStateCount(uint64_t count, absl::Duration timeout) const;
  // The VERSION message, once received.
  std::optional<VersionMessage> version() const;
  // Removes and returns the queued robot messages.
  std::vector<PrimaryPackage> TakeMessages();
  // Why the connection ended (OK while connected).
  absl::Status connection_status() const;

 private:
  void ReadLoop(TcpConnection* connection);
  void Stop();

  const PrimaryClientOptions options_;
  mutable std::mutex mutex_;
  mutable std::condition_variable changed_;
  std::unique_ptr<TcpConnection> connection_;
  std::thread reader_;
  bool connected_ = false;                 // guarded by mutex_
  absl::Status connection_status_;         // guarded by mutex_
  std::optional<RobotState> latest_;       // guarded by mutex_
  uint64_t state_count_ = 0;               // guarded by mutex_
  std::optional<VersionMessage> version_;  // guarded by mutex_
  std::deque<PrimaryPackage> messages_;    // guarded by mutex_
  uint64_t state_count_at_send_ = 0;       // guarded by mutex_
  std::mutex send_mutex_;                  // serialises SendScript
};

}  // namespace cornerpose::ur
