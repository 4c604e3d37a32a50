// What ends a detection early: the caller's deadline, or a caller that went
// away. The detector checks it between its stages and inside its long loops
// (edge scores, RANSAC rounds, the judging of hypotheses) and then returns the
// token's status instead of a result, so an abandoned call frees its worker
// within a few milliseconds rather than at the end of the frame.
#pragma once

#include <atomic>
#include <functional>

#include "absl/status/status.h"
#include "absl/strings/string_view.h"
#include "absl/time/time.h"

namespace cornerpose {

class CancelToken {
 public:
  // Never stops (unless Cancel() is called).
  CancelToken() = default;
  // Stops at `deadline`, or once `cancelled` returns true. `cancelled` is
  // polled from the detector's threads, so it must be thread-safe and cheap
  // (an atomic flag, grpc::ServerContext::IsCancelled).
  explicit CancelToken(absl::Time deadline, std::function<bool()> cancelled = nullptr);
  CancelToken(const CancelToken&) = delete;
  CancelToken& operator=(const CancelToken&) = delete;

  // Stops the detection (any thread).
  void Cancel() const;
  // True once the deadline passed, Cancel() was called or `cancelled` said
  // so; it stays true. Thread-safe; costs a clock read.
  bool Stopped() const;
  // OK while not stopped; else DEADLINE_EXCEEDED or CANCELLED, naming the
  // stage it stopped in.
  absl::Status Check(absl::string_view stage) const;

 private:
  enum State : int { kRunning = 0, kDeadline = 1, kCancelled = 2 };
  absl::Time deadline_ = absl::InfiniteFuture();
  std::function<bool()> cancelled_;
  mutable std::atomic<int> state_{kRunning};
};

// For the stages' loops, which take an optional token.
inline bool StopRequested(const CancelToken* token) { return token != nullptr && token->Stopped(); }

}  // namespace cornerpose
