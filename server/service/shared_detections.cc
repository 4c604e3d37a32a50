#include "server/service/shared_detections.h"

#include <chrono>
#include <iterator>
#include <utility>

#include "server/service/carried_detections.h"

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
    std::shared_ptr<const SharedDetection> last = it != latest_.end() ? it->second.lock() : nullptr;
    for (auto e = latest_.begin(); e != latest_.end();) {
      e = e->second.expired() ? latest_.erase(e) : std::next(e);
    }
    entry = std::make_shared<SharedDetection>();
    entry->frame_id = frame.id;
    entry->options = options;
    UseFrameCamera(frame.camera, &entry->options);  // as Detect does
    if (std::shared_ptr<const SharedDetection> carrier = Carrier(last, frame, entry->options)) {
      entry->detected_frame_id = carrier->frame_id;
      entry->result = carrier->result;
      entry->detected = std::move(carrier);
      entry->frame = std::make_shared<const Frame>(std::move(frame));
      latest_[key] = entry;
      ++carried_;
      return entry;
    }
    entry->detected_frame_id = frame.id;
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

std::shared_ptr<const SharedDetection> SharedDetections::Carrier(
    const std::shared_ptr<const SharedDetection>& last, const Frame& frame,
    const DetectorOptions& options) const {
  if (!carry_unchanged_ || last == nullptr) return nullptr;
  // Always against the frame detected on, so that slow drift adds up.
  const std::shared_ptr<const SharedDetection> detected =
      last->detected != nullptr ? last->detected : last;
  // Only a finished detection without error is carried (one still running
  // is shared by the streams on its own frame).
  if (detected->result.wait_for(std::chrono::seconds(0)) != std::future_status::ready ||
      !detected->result.get().ok()) {
    return nullptr;
  }
  return ShowsSameScene(*detected->frame, frame, options) ? detected : nullptr;
}

uint64_t SharedDetections::started() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return started_;
}

uint64_t SharedDetections::carried() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return carried_;
}

}  // namespace cornerpose::server
