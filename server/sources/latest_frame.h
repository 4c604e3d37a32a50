// What every frame source shares: its newest frames and its state, guarded
// for the source's own thread (which publishes) and any number of readers
// (which wait for a frame newer than the last they saw). Keeping only the
// last kKeptFrames is what makes a slow reader skip frames instead of
// falling ever further behind.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <mutex>
#include <optional>
#include <string>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "absl/time/time.h"
#include "server/sources/frame_source.h"

namespace cornerpose::server {

class LatestFrame {
 public:
  // `label` names the source in errors, e.g. "source 'bin'".
  explicit LatestFrame(std::string label) : label_(std::move(label)) {}

  // FrameSource::GrabNewerThan: the newest frame with id > last_id, waiting
  // up to `timeout`. UNAVAILABLE when the source failed (with the reason),
  // was stopped, or had no newer frame in time; OUT_OF_RANGE when it
  // finished with no newer frame.
  absl::StatusOr<Frame> GrabNewerThan(uint64_t last_id, absl::Duration timeout) const;
  // FrameSource::GrabAfter.
  absl::StatusOr<Frame> GrabAfter(uint64_t last_id, absl::Duration timeout) const;
  SourceStatus state() const;

  // The source's thread: a new frame (the source is then RUNNING), or a new
  // state. Both wake every waiting reader; ignored once stopped.
  void Publish(Frame frame);
  void SetState(SourceState state, std::string reason);

  // Wakes every waiter for good (the source is shutting down).
  void Stop();
  bool stopping() const;
  // Waits `duration` or until Stop; false when stopped.
  bool SleepFor(absl::Duration duration) const;

 private:
  const std::string label_;
  mutable std::mutex mutex_;
  mutable std::condition_variable changed_;
  // Grabs the newest frame, or with `next` the oldest kept after last_id.
  absl::StatusOr<Frame> Grab(uint64_t last_id, absl::Duration timeout, bool next) const;

  std::deque<Frame> kept_;  // oldest first, at most kKeptFrames; guarded by mutex_
  SourceStatus status_;     // guarded by mutex_
  bool stopping_ = false;   // guarded by mutex_
};

}  // namespace cornerpose::server
