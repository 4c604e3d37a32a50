// A FrameSource reading the depth stream of an OpenNI2 device: a live camera
// (Kinect v1, Xtion, anything with an OpenNI2 driver, or the project's
// virtual camera, tools/virtual_camera) or an .oni recording, which OpenNI2
// plays back as a device.
#pragma once

#include <string>
#include <thread>

#include "absl/status/status.h"
#include "absl/time/time.h"
#include "server/sources/frame_source.h"
#include "server/sources/latest_frame.h"

namespace cornerpose::server {

struct OpenNi2SourceOptions {
  // The URI names an .oni file: it must be readable, `loop` and
  // `playback_speed` apply, and without loop the source finishes after the
  // last frame. Otherwise a live device ("" = the first device OpenNI2
  // lists).
  bool recording = false;
  // Recordings: start again after the last frame, or finish.
  bool loop = true;
  // Recordings: playback rate relative to the recording's own timing; > 0.
  double playback_speed = 1.0;
  // After a failure (no device, unreadable file, frames stopped), wait this
  // long before opening again, doubling up to retry_max_delay; reset by a
  // frame.
  absl::Duration retry_delay = absl::Milliseconds(500);
  absl::Duration retry_max_delay = absl::Seconds(10);
  // An open device that sends no frame for this long is taken as gone
  // (unplugged) and reopened.
  absl::Duration frame_timeout = absl::Seconds(5);
};

// Depth frames (PIXEL_FORMAT_DEPTH_1_MM or DEPTH_100_UM) become metric
// organized clouds through the stream's field of view: fx = width / (2
// tan(hfov / 2)), fy likewise from vfov, (cx, cy) = ((width - 1) / 2,
// (height - 1) / 2), as OpenNI2 itself converts depth to world. Only the
// newest frame is kept. A failure puts the source in kFailed with the reason
// (and when it retries) and the source keeps retrying until destroyed; it
// never throws or stops the process.
class OpenNi2Source final : public FrameSource {
 public:
  // Starts the capture thread.
  OpenNi2Source(std::string name, std::string uri, OpenNi2SourceOptions options = {});
  // Stops the thread and closes the device.
  ~OpenNi2Source() override;

  OpenNi2Source(const OpenNi2Source&) = delete;
  OpenNi2Source& operator=(const OpenNi2Source&) = delete;

  const std::string& name() const override { return name_; }
  // "openni2:URI" or "oni:FILE".
  std::string description() const override;
  absl::StatusOr<Frame> GrabNewerThan(uint64_t last_id, absl::Duration timeout) override;
  absl::StatusOr<Frame> GrabAfter(uint64_t last_id, absl::Duration timeout) override;
  SourceStatus state() const override;
  // A device (the virtual camera included: it renders the world as it is);
  // an .oni recording is a replay.
  bool live() const override { return !options_.recording; }

 private:
  // What ended a capture session.
  enum class SessionEnd { kStopping, kFinished, kFailed };

  void Run();
  // Opens the device and captures until stopped, finished or failed; a
  // failure's reason goes to *reason.
  SessionEnd Capture(std::string* reason);
  // Numbers, stamps and publishes a captured frame.
  void Publish(Frame frame);

  const std::string name_;
  const std::string uri_;
  const OpenNi2SourceOptions options_;

  LatestFrame frames_;
  uint64_t next_id_ = 1;    // capture thread only
  bool delivered_ = false;  // capture thread only: a frame since the last failure
  std::thread thread_;
};

}  // namespace cornerpose::server
