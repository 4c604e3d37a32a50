// The daemon's view of the perception service: one StreamDetections call on
// a background thread, re-opened with exponential back-off whenever it ends
// (the service restarted, the network dropped), keeping only the newest
// detection. The cell asks for a detection from a frame captured after its
// last move, so a frame that saw the arm, or the box it has just taken, is
// never used.
#pragma once

#include <grpcpp/security/credentials.h>

#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "absl/time/time.h"
#include "common/box/box_types.h"

namespace grpc {
class ClientContext;
}

namespace cornerpose::robot_client {

struct PerceptionSubscriberOptions {
  // host:port of the cornerpose perception service.
  std::string server = "localhost:50051";
  // The service's frame source to subscribe to.
  std::string source;
  // The box size: a model the service knows (e.g. "carton_s"), or explicit
  // dimensions when `box` is set (then box_model is ignored).
  std::string box_model;
  std::optional<BoxDims> box;
  // Back-off between attempts to (re)open the stream: starts at `initial`,
  // doubles per failed attempt up to `max`, resets once a frame arrives.
  absl::Duration initial_backoff = absl::Milliseconds(200);
  absl::Duration max_backoff = absl::Seconds(5);
  // A detection received longer ago than this (this machine's clock) is
  // not used: the stream has stalled.
  absl::Duration max_frame_age = absl::Seconds(2);
  // The channel's credentials (MakeChannelCredentials, common/grpc_security);
  // null = plaintext. tls_server_name, when set, is the name the server's
  // certificate must carry.
  std::shared_ptr<grpc::ChannelCredentials> credentials;
  std::string tls_server_name;
};

// One frame's detected boxes and where they came from.
struct FrameDetection {
  // Best score first.
  std::vector<DetectedBox> boxes;
  // The size the server detected with (it resolves model names); unset
  // from a server that does not say.
  std::optional<BoxDims> box_dims;
  std::string source;
  // Whether the source is a camera seeing the scene now; false from a
  // replay (or a server that does not say): see allow_replay.
  bool source_live = false;
  uint64_t frame_id = 0;
  absl::Time capture_time;
  // The device's own time of the frame, microseconds (0 when not given).
  uint64_t device_timestamp_us = 0;
  // Which stream delivered it (one per (re)opened subscription; frame ids
  // are ordered within one) and when it arrived here.
  uint64_t stream = 0;
  absl::Time received;
};

// Which frames are fresh: stamped after `not_before` by the server and, in
// the same stream, with a frame id of at least `min_frame_id` (the source's
// own frame order: the frame in flight when a motion ended may have been
// exposed during it, so it is skipped too).
struct FrameFloor {
  absl::Time not_before = absl::InfinitePast();
  uint64_t stream = 0;
  uint64_t min_frame_id = 0;
};

class PerceptionSubscriber {
 public:
  explicit PerceptionSubscriber(PerceptionSubscriberOptions options);
  // Cancels the stream and joins the thread.
  ~PerceptionSubscriber();
  PerceptionSubscriber(const PerceptionSubscriber&) = delete;
  PerceptionSubscriber& operator=(const PerceptionSubscriber&) = delete;

  // Starts the background stream (once).
  void Start();
  // Cancels the stream; Wait* return nullopt from then on.
  void Stop();

  // The newest detection of a frame captured strictly after `not_before`,
  // waiting up to `timeout` for one; nullopt when none came.
  std::optional<FrameDetection> WaitForFrameAfter(absl::Time not_before, absl::Duration timeout);
  // The newest detection fresh by `floor` and received within
  // max_frame_age; nullopt when none came within `timeout`.
  std::optional<FrameDetection> WaitForFrame(const FrameFloor& floor, absl::Duration timeout);
  // The floor for "after now": the server's frames stamped after now and,
  // in the current stream, ids past the newest received + 1.
  FrameFloor FloorAfterNow() const;

  // True while the stream is open and has delivered a frame.
  bool connected() const;
  // Why the last stream ended (empty before any failure).
  std::string last_error() const;
  // Detections received since Start.
  uint64_t frames_received() const;

 private:
  void Run();
  // Sleeps up to `d` unless stopped; false when stopped.
  bool SleepUnlessStopped(absl::Duration d);

  const PerceptionSubscriberOptions options_;
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  bool started_ = false;                    // guarded by mutex_
  bool stopping_ = false;                   // guarded by mutex_
  bool connected_ = false;                  // guarded by mutex_
  std::string last_error_;                  // guarded by mutex_
  uint64_t frames_received_ = 0;            // guarded by mutex_
  std::optional<FrameDetection> latest_;    // guarded by mutex_; reset when the stream drops
  uint64_t stream_ = 0;                     // guarded by mutex_
  grpc::ClientContext* context_ = nullptr;  // guarded by mutex_; the open call
  std::thread thread_;
};

}  // namespace cornerpose::robot_client
