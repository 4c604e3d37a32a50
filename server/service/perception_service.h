// The PerceptionService handlers, on gRPC's callback API. Thin: they convert
// the request (detect_request.h), run the detector on the DetectionPool and
// convert the result (conversion.h); errors leave as the RPC status.
#pragma once

#include <atomic>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "common/perception/detector.h"
#include "cornerpose/v1/perception_service.grpc.pb.h"
#include "server/service/detect_request.h"
#include "server/service/detection_pool.h"
#include "server/sources/frame_source.h"

namespace cornerpose::server {

class PerceptionServiceImpl final : public v1::PerceptionService::CallbackService {
 public:
  // `pool` runs the detections and must outlive every RPC (the server's
  // shutdown waits for them). `defaults` are the detector options a request
  // starts from; its box is ignored. `box_models` are the server's own named
  // box sizes (before the built-in ones). `sources` (unique names) are what
  // requests can name; the service owns them, so they stop after the server.
  PerceptionServiceImpl(DetectionPool* pool, DetectorOptions defaults,
                        std::vector<std::unique_ptr<FrameSource>> sources = {},
                        BoxModels box_models = {});

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

 private:
  DetectionPool* pool_;
  const DetectorOptions defaults_;
  const BoxModels box_models_;
  // By name; fixed after construction, so read without a lock.
  std::map<std::string, std::unique_ptr<FrameSource>> sources_;
  std::atomic<bool> stopping_streams_{false};
};

}  // namespace cornerpose::server
