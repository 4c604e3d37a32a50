// The StreamDetections reactor: detects on each new frame of a source and
// writes the results, one write in flight at a time.
#pragma once

#include <atomic>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "common/perception/detector.h"
#include "cornerpose/v1/perception_service.grpc.pb.h"
#include "server/service/detect_response.h"
#include "server/service/detection_pool.h"
#include "server/service/shared_detections.h"
#include "server/sources/frame_source.h"

namespace cornerpose::server {

// Each stream has a thread that waits for frames (so waiting never occupies
// a detection worker), gets each frame's detection from `shared` (run on the
// pool, so streams share the bound on concurrent detections with Detect, and
// shared with every stream of the same source and parameters), and waits for the write
// before grabbing again: a slow client therefore gets the newest frame next,
// never a backlog. Deletes itself when the RPC is done.
class StreamDetectionsReactor final : public grpc::ServerWriteReactor<v1::DetectResponse> {
 public:
  // Finishes at once with `error` (a request refused before streaming).
  explicit StreamDetectionsReactor(const grpc::Status& error);
  // Streams until cancelled, the source ends or fails, or *stopping is set
  // (server shutdown). `share_key` names the source and the parameters that
  // change the detection. With `every_frame` it asks the source for the
  // frame after the last (FrameSource::GrabAfter), not the newest.
  // *open_streams is decremented when the RPC is done.
  // Everything pointed to outlives the RPC.
  StreamDetectionsReactor(DetectionPool* pool, SharedDetections* shared, std::string share_key,
                          FrameSource* source, DetectorOptions options, ResponseContents contents,
                          bool every_frame, const std::atomic<bool>* stopping,
                          std::atomic<int>* open_streams);

  void OnWriteDone(bool ok) override;
  void OnCancel() override;
  void OnDone() override;

 private:
  void Run();
  // Why the stream ends now, or OK to go on.
  grpc::Status ShouldStop();

  DetectionPool* pool_ = nullptr;
  SharedDetections* shared_ = nullptr;
  const std::string share_key_;
  FrameSource* source_ = nullptr;
  const DetectorOptions options_;
  const ResponseContents contents_;
  const bool every_frame_ = false;
  const std::atomic<bool>* stopping_ = nullptr;
  std::atomic<int>* open_streams_ = nullptr;

  std::mutex mutex_;
  std::condition_variable changed_;
  bool write_pending_ = false;                      // guarded by mutex_
  bool write_ok_ = true;                            // guarded by mutex_
  bool cancelled_ = false;                          // guarded by mutex_
  v1::DetectResponse response_;                     // owned by the write in flight
  std::shared_ptr<const SharedDetection> current_;  // Run's thread only
  std::thread thread_;
};

}  // namespace cornerpose::server
