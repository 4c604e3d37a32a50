#include "server/service/shared_detections.h"

#include <iterator>
#include <utility>

namespace cornerpose::server {

std::shared_ptr<const SharedDetection> SharedDetections::Get(const std::string& key, Frame frame,
                                                              const DetectorOptions& options,
                                                              DetectionPool* pool) {
  auto promise = std::make_shared<std::promise<absl::StatusOr<Detection>>>();
  std::shared_ptr<SharedDetection> entry;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = latest_.find(key);
    if (it != latest_.end()) {
      if (std::shared_ptr<const SharedDetection> held = it->second.lock();
          held != nullptr && held->frame_id == frame.id) {
        return held;
      }
    }
    for (auto e = latest_.begin(); e != latest_.end();) {
      e = e->second.expired() ? latest_.erase(e) : std::next(e);
    }
    entry = std::make_shared<SharedDetection>();
    entry->frame_id = frame.id;
    entry->options = options;
    UseFrameCamera(frame.camera, &entry->options);  // as Detect does
    entry->frame = std::make_shared<const Frame>(std::move(frame));
    entry->result = promise->get_future().share();
    latest_[key] = entry;
    ++started_;
  }
  // The task holds the frame and options, not the entry, so an entry every
  // stream dropped still expires.
  // A detection whose entry every stream dropped stops (its result would go
  // to no one).
  pool->Submit([promise, frame = entry->frame, opts = entry->options,
                wanted = std::weak_ptr<SharedDetection>(entry)] {
    const CancelToken cancel(absl::InfiniteFuture(), [&wanted] { return wanted.expired(); });
    promise->set_value(DetectBoxes(frame->cloud, opts, cancel));
  });
  return entry;
}

uint64_t SharedDetections::started() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return started_;
}

}  // namespace cornerpose::server
