// Fan-out for StreamDetections: streams on the same source with the same
// detection parameters share one detection per frame, so N viewers of a
// camera cost one detector run per frame, not N. And a frame that shows the
// same scene as the last one detected on (CompareFrames: a cell's pallet
// between two picks, new sensor noise on every frame) gets that detection
// again without a detector run.
#pragma once

#include <cstdint>
#include <future>
#include <map>
#include <memory>
#include <mutex>
#include <string>

#include "absl/status/statusor.h"
#include "common/perception/detector.h"
#include "server/service/detection_pool.h"
#include "server/sources/frame_source.h"

namespace cornerpose::server {

// One frame's detection, shared by the streams that asked for it.
struct SharedDetection {
  uint64_t frame_id = 0;
  std::shared_ptr<const Frame> frame;
  DetectorOptions options;  // with the frame's camera applied
  std::shared_future<absl::StatusOr<Detection>> result;
  // The frame the detection ran on: frame_id, or an earlier frame's whose
  // detection this one carries (then `detected` holds that entry).
  uint64_t detected_frame_id = 0;
  std::shared_ptr<const SharedDetection> detected;
};

class SharedDetections {
 public:
  // With `carry_unchanged`, a frame showing the same scene as the last frame
  // detected on under the same key carries that detection.
  explicit SharedDetections(bool carry_unchanged = true) : carry_unchanged_(carry_unchanged) {}

  // The detection of `frame` under `key` (the source and the parameters that
  // change the detection): the one another stream already started for this
  // frame, or a new one run on `pool`. The entry lives while a stream holds
  // it, so a stream keeps the last one until it has the next.
  std::shared_ptr<const SharedDetection> Get(const std::string& key, Frame frame,
                                             const DetectorOptions& options, DetectionPool* pool);
  // Detections started (not shared, not carried) since construction.
  uint64_t started() const;
  // Frames that carried an earlier frame's detection.
  uint64_t carried() const;

 private:
  // The entry whose detection `frame` may carry: the last one detected on
  // under the key, finished without error, showing the same scene.
  std::shared_ptr<const SharedDetection> Carrier(const std::shared_ptr<const SharedDetection>& last,
                                                 const Frame& frame,
                                                 const DetectorOptions& options) const;

  const bool carry_unchanged_;
  mutable std::mutex mutex_;
  // Latest per key; expired entries are dropped as new ones go in.
  std::map<std::string, std::weak_ptr<const SharedDetection>> latest_;  // guarded by mutex_
  uint64_t started_ = 0;                                                // guarded by mutex_
  uint64_t carried_ = 0;                                                // guarded by mutex_
};

}  // namespace cornerpose::server
