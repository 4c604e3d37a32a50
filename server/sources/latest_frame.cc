#include "server/sources/latest_frame.h"

#include <algorithm>
#include <utility>

#include "absl/strings/str_cat.h"

namespace cornerpose::server {

absl::StatusOr<Frame> LatestFrame::GrabNewerThan(uint64_t last_id, absl::Duration timeout) const {
  return Grab(last_id, timeout, false);
}

absl::StatusOr<Frame> LatestFrame::GrabAfter(uint64_t last_id, absl::Duration timeout) const {
  return Grab(last_id, timeout, true);
}

absl::StatusOr<Frame> LatestFrame::Grab(uint64_t last_id, absl::Duration timeout, bool next) const {
  std::unique_lock<std::mutex> lock(mutex_);
  const auto newer = [&] { return !kept_.empty() && kept_.back().id > last_id; };
  const auto ready = [&] {
    return stopping_ || status_.state == SourceState::kFailed ||
           status_.state == SourceState::kFinished || newer();
  };
  changed_.wait_for(lock, absl::ToChronoNanoseconds(std::max(timeout, absl::ZeroDuration())),
                    ready);
  if (status_.state == SourceState::kFailed) {
    return absl::UnavailableError(absl::StrCat(label_, " failed: ", status_.reason));
  }
  if (newer()) {
    // A reader whose next frame is no longer kept skips to the newest.
    if (!next || kept_.front().id > last_id + 1) return kept_.back();
    for (const Frame& frame : kept_) {
      if (frame.id > last_id) return frame;  // oldest first
    }
  }
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
    kept_.push_back(std::move(frame));
    while (kept_.size() > static_cast<size_t>(kKeptFrames)) kept_.pop_front();
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
