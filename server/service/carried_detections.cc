#include "server/service/carried_detections.h"

#include <algorithm>
#include <utility>

#include "common/perception/camera_model.h"
#include "common/perception/frame_change.h"

namespace cornerpose::server {

bool ShowsSameScene(const Frame& before, const Frame& after, const DetectorOptions& options) {
  FrameChangeOptions compare;
  compare.box_side_m = std::min({options.box.l, options.box.b, options.box.h});
  if (options.camera) {
    compare.focal_px = options.camera->fx;
  } else if (absl::StatusOr<CameraIntrinsics> k = EstimateIntrinsics(after.cloud); k.ok()) {
    compare.focal_px = k->fx;
  }
  absl::StatusOr<FrameChange> change = CompareFrames(before.cloud, after.cloud, compare);
  return change.ok() && change->same_scene;
}

std::optional<CarriedDetections::Carried> CarriedDetections::Find(const std::string& key,
                                                                  const Frame& frame,
                                                                  const DetectorOptions& options) {
  if (!enabled_) return std::nullopt;
  std::shared_ptr<const Frame> before;
  std::shared_ptr<const Detection> detection;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = std::find_if(entries_.begin(), entries_.end(),
                           [&](const Entry& e) { return e.key == key; });
    if (it == entries_.end()) return std::nullopt;
    entries_.splice(entries_.begin(), entries_, it);
    before = it->frame;
    detection = it->detection;
  }
  // Compared outside the lock: other calls need not wait for it.
  if (!ShowsSameScene(*before, frame, options)) return std::nullopt;
  std::lock_guard<std::mutex> lock(mutex_);
  ++carried_;
  return Carried{std::move(detection), before->id};
}

void CarriedDetections::Store(const std::string& key, std::shared_ptr<const Frame> frame,
                              const Detection& detection) {
  if (!enabled_ || max_keys_ == 0) return;
  auto kept = std::make_shared<const Detection>(detection);
  std::lock_guard<std::mutex> lock(mutex_);
  auto it =
      std::find_if(entries_.begin(), entries_.end(), [&](const Entry& e) { return e.key == key; });
  if (it != entries_.end()) entries_.erase(it);
  entries_.push_front({key, std::move(frame), std::move(kept)});
  while (entries_.size() > max_keys_) entries_.pop_back();
}

uint64_t CarriedDetections::carried() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return carried_;
}

}  // namespace cornerpose::server
