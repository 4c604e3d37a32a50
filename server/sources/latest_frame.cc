#include "server/sources/latest_frame.h"

#include <algorithm>
#include <utility>

#include "absl/strings/str_cat.h"

namespace cornerpose::server {

absl::StatusOr<Frame> LatestFrame::GrabNewerThan(uint64_t last_id, absl::Duration timeout) const {
  std::unique_lock<std::mutex> lock(mutex_);
  const auto ready = [&] {
    return stopping_ || status_.state == SourceState::kFailed ||
           status_.state == SourceState::kFinished || (newest_ && newest_->id > last_id);
  };
  changed_.wait_for(lock, absl::ToChronoNanoseconds(std::max(timeout, absl::ZeroDuration())),
                    ready);
  if (status_.state == SourceState::kFailed) {
    return absl::UnavailableError(absl::StrCat(label_, " failed: ", status_.reason));
  }
  if (newest_ && newest_->id > last_id) return *newest_;
  if (status_.state == SourceState::kFinished) {
    return absl::OutOfRangeError(absl::StrCat(label_, " finished"));
  }
  if (stopping_) return absl::UnavailableError(absl::StrCat(label_, " stopped"));
  return absl::UnavailableError(
      absl::StrCat("no new frame from ", label_, " within ", absl::FormatDuration(timeout)));
}

SourceStatus LatestFrame::state() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return status_;
}

void LatestFrame::Publish(Frame frame) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (stopping_) return;
    newest_ = std::move(frame);
    status_ = {SourceState::kRunning, ""};
  }
  changed_.notify_all();
}

void LatestFrame::SetState(SourceState state, std::string reason) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (stopping_) return;
    status_ = {state, std::move(reason)};
  }
  changed_.notify_all();
}

void LatestFrame::Stop() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  changed_.notify_all();
}

bool LatestFrame::stopping() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return stopping_;
}

bool LatestFrame::SleepFor(absl::Duration duration) const {
  std::unique_lock<std::mutex> lock(mutex_);
  return !changed_.wait_for(lock, absl::ToChronoNanoseconds(duration), [&] { return stopping_; });
}

}  // namespace cornerpose::server
