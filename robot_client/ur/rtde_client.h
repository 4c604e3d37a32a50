// Client for RTDE (port 30004), protocol 2: handshake (protocol version,
// URControl version, output recipe, start), then a reader thread decoding
// the data packages into RtdeState.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "absl/time/time.h"
#include "robot_client/ur/pose.h"
#include "robot_client/ur/rtde.h"
#include "robot_client/ur/tcp.h"

namespace cornerpose::ur {

struct RtdeState {
  uint64_t sequence = 0;   // 1 for the first package, +1 per package
  double timestamp = 0.0;  // s since controller start
  Joints target_q{};
  Joints actual_q{};
  Joints actual_qd{};
  UrPose actual_tcp_pose;
  UrPose target_tcp_pose;
  uint64_t digital_outputs = 0;     // actual_digital_output_bits
  uint64_t digital_inputs = 0;      // actual_digital_input_bits
  int32_t robot_mode = 0;           // RobotMode (dashboard.h)
  int32_t safety_mode = 0;          // SafetyMode (dashboard.h)
  uint32_t safety_status_bits = 0;  // bit 2: protective stopped
  uint32_t robot_status_bits = 0;   // bit 1: program running
  uint32_t runtime_state = 0;       // 1 stopped, 2 playing, 4 paused
  double speed_scaling = 0.0;
  double target_speed_fraction = 0.0;
  // When the package arrived (this machine's clock): its age is how stale
  // the state is.
  absl::Time received = absl::InfinitePast();
};

struct RtdeClientOptions {
  // Requested output frequency [Hz]; capped at 125 for a controller older
  // than 5.0 (CB3) and 500 otherwise.
  double frequency = 125.0;
  // A connection that sends nothing for this long is taken as lost (open
  // but silent: half-open, or the controller hung). Infinite: never.
  absl::Duration read_timeout = absl::InfiniteDuration();
  // Latest() refuses a state older than this (DEADLINE_EXCEEDED): a stalled
  // stream must not be planned from. Infinite: any age.
  absl::Duration max_age = absl::InfiniteDuration();
};

// The output recipe the client requests, in order.
const std::vector<std::string>& RtdeClientOutputs();

// Thread-safe. Owns a reader thread from Connect until Close / destruction.
class RtdeClient {
 public:
  explicit RtdeClient(RtdeClientOptions options = {});
  ~RtdeClient();

  RtdeClient(const RtdeClient&) = delete;
  RtdeClient& operator=(const RtdeClient&) = delete;

  // Connects, runs the handshake and waits for the first data package, all
  // within `timeout`. FAILED_PRECONDITION when the controller refuses a
  // step (protocol 2, a variable, start).
  absl::Status Connect(absl::string_view host, int port = 30004,
                       absl::Duration timeout = absl::Seconds(5));
  bool connected() const;
  void Close();

  // The controller version from the handshake.
  std::optional<UrcontrolVersion> controller_version() const;

  // The newest state; UNAVAILABLE when not connected, DEADLINE_EXCEEDED
  // (with its age) when it is older than options.max_age.
  absl::StatusOr<RtdeState> Latest() const;
  // The same with another age limit (the watchdog of a running program
  // allows more than the planner does).
  absl::StatusOr<RtdeState> Latest(absl::Duration max_age) const;
  // The first state with sequence > `sequence`; DEADLINE_EXCEEDED, or
  // UNAVAILABLE when the connection is lost.
  absl::StatusOr<RtdeState> WaitForNewer(uint64_t sequence, absl::Duration timeout) const;

 private:
  void ReadLoop(TcpConnection* connection, RtdeFramer framer, uint8_t recipe_id,
                std::vector<RtdeType> types);
  void Stop();

  const RtdeClientOptions options_;
  mutable std::mutex mutex_;
  mutable std::condition_variable changed_;
  std::unique_ptr<TcpConnection> connection_;
  std::thread reader_;
  bool connected_ = false;                   // guarded by mutex_
  absl::Status connection_status_;           // guarded by mutex_
  std::optional<RtdeState> latest_;          // guarded by mutex_
  std::optional<UrcontrolVersion> version_;  // guarded by mutex_
};

}  // namespace cornerpose::ur
