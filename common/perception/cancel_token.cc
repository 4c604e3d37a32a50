#include "common/perception/cancel_token.h"

#include <utility>

#include "absl/strings/str_cat.h"

namespace cornerpose {

CancelToken::CancelToken(absl::Time deadline, std::function<bool()> cancelled)
    : deadline_(deadline), cancelled_(std::move(cancelled)) {}

void CancelToken::Cancel() const {
  int running = kRunning;
  state_.compare_exchange_strong(running, kCancelled, std::memory_order_relaxed);
}

bool CancelToken::Stopped() const {
  if (state_.load(std::memory_order_relaxed) != kRunning) return true;
  int next = kRunning;
  if (cancelled_ && cancelled_()) {
    next = kCancelled;
  } else if (deadline_ != absl::InfiniteFuture() && absl::Now() >= deadline_) {
    next = kDeadline;
  } else {
    return false;
  }
  int running = kRunning;
  state_.compare_exchange_strong(running, next, std::memory_order_relaxed);
  return true;
}

absl::Status CancelToken::Check(absl::string_view stage) const {
  if (!Stopped()) return absl::OkStatus();
  if (state_.load(std::memory_order_relaxed) == kDeadline) {
    return absl::DeadlineExceededError(absl::StrCat("deadline passed during ", stage));
  }
  return absl::CancelledError(absl::StrCat("cancelled during ", stage));
}

}  // namespace cornerpose
