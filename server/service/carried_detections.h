// The last detection on each source under each set of parameters, for
// Detect calls on a source: a call whose newest frame shows the same scene
// (CompareFrames: warehouse software polling a pallet between two picks)
// gets that detection again without a detector run. Streams carry theirs in
// SharedDetections; both ask ShowsSameScene.
#pragma once

#include <cstddef>
#include <cstdint>
#include <list>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "common/perception/detector.h"
#include "server/sources/frame_source.h"

namespace cornerpose::server {

// Whether `after` shows the same scene as `before` for boxes of
// options.box (CompareFrames with windows the size of the box's smallest
// side, through the camera of `options`, or the one `after`'s cloud implies).
bool ShowsSameScene(const Frame& before, const Frame& after, const DetectorOptions& options);

class CarriedDetections {
 public:
  // Off: Find finds nothing and Store keeps nothing. Keeps the last
  // detection of at most `max_keys` keys, the least recently used dropped.
  explicit CarriedDetections(bool enabled, size_t max_keys = 16)
      : enabled_(enabled), max_keys_(max_keys) {}

  struct Carried {
    std::shared_ptr<const Detection> detection;
    uint64_t frame_id = 0;  // the frame it ran on
  };
  // The detection stored under `key`, when `frame` shows the same scene as
  // the frame it ran on.
  std::optional<Carried> Find(const std::string& key, const Frame& frame,
                              const DetectorOptions& options);
  // Keeps `detection` of `frame` under `key` (replacing what was there).
  void Store(const std::string& key, std::shared_ptr<const Frame> frame,
             const Detection& detection);
  uint64_t carried() const;

 private:
  struct Entry {
    std::string key;
    std::shared_ptr<const Frame> frame;
    std::shared_ptr<const Detection> detection;
  };
  const bool enabled_;
  const size_t max_keys_;
  mutable std::mutex mutex_;
  std::list<Entry> entries_;  // most recently used first; guarded by mutex_
  uint64_t carried_ = 0;      // guarded by mutex_
};

}  // namespace cornerpose::server
