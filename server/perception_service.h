// The PerceptionService handlers, on gRPC's callback API. Thin: they convert
// the request (detect_request.h), run the detector on the DetectionPool and
// convert the result (conversion.h); errors leave as the RPC status.
#pragma once

#include "common/perception/detector.h"
#include "cornerpose/v1/perception_service.grpc.pb.h"
#include "server/detection_pool.h"

namespace cornerpose::server {

class PerceptionServiceImpl final : public v1::PerceptionService::CallbackService {
 public:
  // `pool` runs the detections and must outlive every RPC (the server's
  // shutdown waits for them). `defaults` are the detector options a request
  // starts from; its box is ignored.
  PerceptionServiceImpl(DetectionPool* pool, DetectorOptions defaults);

  grpc::ServerUnaryReactor* Detect(grpc::CallbackServerContext* context,
                                   const v1::DetectRequest* request,
                                   v1::DetectResponse* response) override;

  grpc::ServerUnaryReactor* ListSources(grpc::CallbackServerContext* context,
                                        const v1::ListSourcesRequest* request,
                                        v1::ListSourcesResponse* response) override;

 private:
  DetectionPool* pool_;
  const DetectorOptions defaults_;
};

}  // namespace cornerpose::server
