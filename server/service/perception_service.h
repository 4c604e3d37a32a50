// The PerceptionService handlers, on gRPC's callback API. Thin: they convert
// the request (detect_request.h), run the detector on the DetectionPool and
// convert the result (conversion.h); errors leave as the RPC status.
#pragma once

#include <atomic>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "absl/time/time.h"
#include "common/perception/detector.h"
#include "cornerpose/v1/perception_service.grpc.pb.h"
#include "server/service/carried_detections.h"
#include "server/service/detect_request.h"
#include "server/service/detection_pool.h"
#include "server/service/shared_detections.h"
#include "server/sources/frame_source.h"

namespace cornerpose::server {

// What the handlers admit (ServerOptions documents each, with its range).
struct ServiceLimits {
  int max_streams = 16;
  absl::Duration default_deadline = absl::Seconds(10);
  absl::Duration max_deadline = absl::Seconds(60);
  bool carry_unchanged_frames = true;  // SharedDetections
};

class PerceptionServiceImpl final : public v1::PerceptionService::CallbackService {
 public:
  // `pool` runs the detections and must outlive every RPC (the server's
  // shutdown waits for them). `defaults` are the detector options a request
  // starts from; its box is ignored. `box_models` are the server's own named
  // box sizes (before the built-in ones). `sources` (unique names) are what
  // requests can name; the service owns them, so they stop after the server.
  PerceptionServiceImpl(DetectionPool* pool, const DetectorOptions& defaults,
                        std::vector<std::unique_ptr<FrameSource>> sources = {},
                        BoxModels box_models = {}, ServiceLimits limits = {});

  grpc::ServerUnaryReactor* Detect(grpc::CallbackServerContext* context,
                                   const v1::DetectRequest* request,
                                   v1::DetectResponse* response) override;

  grpc::ServerUnaryReactor* ListSources(grpc::CallbackServerContext* context,
                                        const v1::ListSourcesRequest* request,
                                        v1::ListSourcesResponse* response) override;

  grpc::ServerWriteReactor<v1::DetectResponse>* StreamDetections(
      grpc::CallbackServerContext* context, const v1::StreamDetectionsRequest* request) override;

  // Ends every open stream (UNAVAILABLE) within a poll period. Streams run
  // until cancelled, so the server's shutdown, which waits for RPCs in
  // flight, calls this first.
  void StopStreams() { stopping_streams_ = true; }

  // The server's own box models (the web view resolves its boxes with them).
  const BoxModels& box_models() const { return box_models_; }
  // The sources requests can name, by name (the web view shows them too).
  std::vector<FrameSource*> sources() const {
    std::vector<FrameSource*> out;
    for (const auto& [name, source] : sources_) out.push_back(source.get());
    return out;
  }
  // Detections streams started (shared ones counted once; frames carried
  // not counted), frames carried, and streams open.
  uint64_t stream_detections_started() const { return shared_.started(); }
  uint64_t stream_frames_carried() const { return shared_.carried(); }
  // Detect calls on a source answered with an earlier frame's detection.
  uint64_t detect_calls_carried() const { return carried_.carried(); }
  int open_streams() const { return open_streams_.load(); }

 private:
  DetectionPool* pool_;
  const DetectorOptions defaults_;
  const BoxModels box_models_;
  // By name; fixed after construction, so read without a lock.
  std::map<std::string, std::unique_ptr<FrameSource>> sources_;
  const ServiceLimits limits_;
  SharedDetections shared_;
  // Detect on a source: the last detection per source and parameters.
  CarriedDetections carried_;
  std::atomic<bool> stopping_streams_{false};
  std::atomic<int> open_streams_{0};
};

}  // namespace cornerpose::server
