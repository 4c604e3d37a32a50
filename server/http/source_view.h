// What the web view shows of one source: its newest frames, the frame rate,
// and detections on them for each box a page asks for. A thread per source
// follows the frames; it detects (on the server's DetectionPool, shared with
// Detect and StreamDetections) only for boxes someone watches, at most
// view_max_rate_hz, always on the newest frame, so a slow detector skips
// frames instead of queueing them.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "absl/status/statusor.h"
#include "absl/time/time.h"
#include "common/box/box_models.h"
#include "common/perception/detector.h"
#include "server/http/http_options.h"
#include "server/service/detection_pool.h"
#include "server/sources/frame_source.h"

namespace cornerpose::server {

// A detection the view made, with the frame and the options it used.
struct ViewDetection {
  std::shared_ptr<const Frame> frame;
  Detection detection;
  // The box as the page named it ("carton_s", "0.3,0.2,0.15").
  std::string box_label;
  DetectorOptions options;
};

// The source's line in /api/sources.
struct SourceSummary {
  std::string name;
  std::string description;
  SourceStatus status;
  uint64_t frame_id = 0;  // 0 before the first frame
  std::optional<double> frame_age_s;
  double fps = 0.0;                     // frames in the last 5 s
  std::optional<double> detection_ms;  // the last view detection's total
  std::string box_label;               // the default box
};

class SourceView {
 public:
  // Called on the view's thread after each detection (metrics).
  using DetectionHook = std::function<void(const Detection&)>;

  // `source`, `pool` and `box_models` outlive the view. `defaults` as the
  // service's (its box is replaced).
  SourceView(FrameSource* source, DetectionPool* pool, DetectorOptions defaults,
             const BoxModels* box_models, HttpOptions options, DetectionHook hook = {});
  ~SourceView();
  SourceView(const SourceView&) = delete;
  SourceView& operator=(const SourceView&) = delete;

  const std::string& name() const { return source_->name(); }
  SourceSummary Summary() const;

  // The newest detection with frame id > after_id for `box` ("" = the
  // default), waiting up to `timeout` (and asking the thread to detect for
  // that box). INVALID_ARGUMENT for a bad box; RESOURCE_EXHAUSTED when too
  // many boxes are watched; UNAVAILABLE when none came in time (the source's
  // reason when it failed); DEADLINE_EXCEEDED-free: a timeout is UNAVAILABLE.
  absl::StatusOr<std::shared_ptr<const ViewDetection>> NextDetection(const std::string& box,
                                                                     uint64_t after_id,
                                                                     absl::Duration timeout);
  // Marks `box` watched (an open event stream: +1, closed: -1).
  // INVALID_ARGUMENT / RESOURCE_EXHAUSTED as NextDetection.
  absl::Status Watch(const std::string& box, int delta);

  // A kept frame (the last frames_kept), or nullptr.
  std::shared_ptr<const Frame> FindFrame(uint64_t id) const;

  // Ends the thread (idempotent); waiting calls return UNAVAILABLE.
  void Stop();

 private:
  struct BoxState {
    DetectorOptions options;
    absl::Time last_interest = absl::InfinitePast();
    int watchers = 0;
    absl::Time last_run = absl::InfinitePast();
    std::shared_ptr<const ViewDetection> latest;
    absl::Status error;  // the last detection's failure
  };

  void Run();
  // The box state for `box` under mutex_, creating it.
  absl::StatusOr<BoxState*> BoxLocked(const std::string& box);
  std::string Label(const std::string& box) const { return box.empty() ? options_.view_box : box; }

  FrameSource* const source_;
  DetectionPool* const pool_;
  const DetectorOptions defaults_;
  const BoxModels* const box_models_;
  const HttpOptions options_;
  const DetectionHook hook_;

  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<std::shared_ptr<const Frame>> frames_;  // oldest first; guarded
  std::deque<absl::Time> arrivals_;                  // guarded
  std::map<std::string, BoxState> boxes_;            // by label; guarded
  std::optional<double> last_detection_ms_;          // guarded
  bool stopping_ = false;                            // guarded
  std::thread thread_;
};

}  // namespace cornerpose::server
