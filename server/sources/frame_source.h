// Where the service gets frames from when a request names a source instead of
// sending a cloud: a camera, a recording or a directory of recorded frames.
// Sources run on their own threads and keep only the newest frame, so a slow
// detector drops frames instead of falling behind.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "absl/status/statusor.h"
#include "absl/time/time.h"
#include "common/perception/types.h"

namespace cornerpose::server {

// One captured frame.
struct Frame {
  PointCloud cloud;
  // The camera the cloud came from, when known (depth images).
  std::optional<CameraIntrinsics> camera;
  // Increasing per source, from 1; a gap means frames were dropped.
  uint64_t id = 0;
  absl::Time capture_time;
  // The device's own time of the frame, microseconds from an arbitrary
  // start (OpenNI2's per-frame timestamp; a frame directory's is the frame's
  // index over its rate). Increasing within one pass of a recording.
  uint64_t device_timestamp_us = 0;
  // The name of the source.
  std::string source;
  // A camera seeing the scene now (true), or a replay of recorded frames
  // (.oni files, frame directories): what is in it may not be there.
  bool live = false;
};

enum class SourceState { kStarting, kRunning, kFailed, kFinished };

// The state and, for kFailed, why (otherwise informative or empty).
struct SourceStatus {
  SourceState state = SourceState::kStarting;
  std::string reason;
};

// How many of its newest frames a source keeps for readers a few frames
// behind (FrameSource::GrabAfter): 200 ms at 30 frames a second, 22 MB of
// VGA clouds.
inline constexpr int kKeptFrames = 6;

class FrameSource {
 public:
  virtual ~FrameSource() = default;

  virtual const std::string& name() const = 0;
  // For ListSources: the device, recording or directory.
  virtual std::string description() const = 0;

  // The newest frame, waiting up to `timeout` for the first one.
  // UNAVAILABLE when the source has failed (with the reason) or no frame
  // came in time.
  absl::StatusOr<Frame> Grab(absl::Duration timeout) { return GrabNewerThan(0, timeout); }

  // The newest frame with id > last_id, waiting up to `timeout` for one (how
  // a stream asks for the next frame without seeing one twice). UNAVAILABLE
  // as Grab; OUT_OF_RANGE when the source finished with no newer frame.
  virtual absl::StatusOr<Frame> GrabNewerThan(uint64_t last_id, absl::Duration timeout) = 0;

  // The frame after last_id: the oldest the source still keeps (its last
  // kKeptFrames) with id > last_id, or the newest when the reader has
  // fallen further behind; waiting and errors as GrabNewerThan. How a stream
  // that asked for every frame catches up after a slow detection.
  virtual absl::StatusOr<Frame> GrabAfter(uint64_t last_id, absl::Duration timeout) = 0;

  virtual SourceStatus state() const = 0;

  // Whether its frames come from a camera seeing the scene now (Frame::live).
  virtual bool live() const = 0;
};

// "STARTING", "RUNNING", "FAILED", "FINISHED".
const char* SourceStateName(SourceState state);

}  // namespace cornerpose::server
