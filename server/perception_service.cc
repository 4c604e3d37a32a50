#include "server/perception_service.h"

#include <chrono>
#include <utility>

#include "server/conversion.h"
#include "server/detect_request.h"
#include "server/status_mapping.h"

namespace cornerpose::server {
namespace {

// OK while the caller still wants the answer. Checked before and after the
// detector (which cannot be interrupted), so a request that waited in the
// queue past its deadline costs no detection, and a late one no conversion.
grpc::Status CheckStillWanted(grpc::CallbackServerContext& context) {
  if (context.deadline() <= std::chrono::system_clock::now()) {
    return grpc::Status(grpc::StatusCode::DEADLINE_EXCEEDED, "deadline exceeded");
  }
  if (context.IsCancelled()) return grpc::Status(grpc::StatusCode::CANCELLED, "cancelled");
  return grpc::Status::OK;
}

grpc::Status RunDetect(grpc::CallbackServerContext& context, const v1::DetectRequest& request,
                       const DetectorOptions& defaults, v1::DetectResponse& response) {
  if (grpc::Status s = CheckStillWanted(context); !s.ok()) return s;
  absl::StatusOr<DetectorOptions> options = DetectorOptionsFromRequest(request, defaults);
  if (!options.ok()) return ToGrpcStatus(options.status());
  absl::StatusOr<PointCloud> cloud = CloudFromRequest(request);
  if (!cloud.ok()) return ToGrpcStatus(cloud.status());
  if (grpc::Status s = CheckStillWanted(context); !s.ok()) return s;

  absl::StatusOr<Detection> detection = DetectBoxes(*cloud, *options);
  if (!detection.ok()) return ToGrpcStatus(detection.status());

  if (grpc::Status s = CheckStillWanted(context); !s.ok()) return s;
  response = DetectionToProto(*detection, request.include_edge_points());
  return grpc::Status::OK;
}

}  // namespace

PerceptionServiceImpl::PerceptionServiceImpl(DetectionPool* pool, DetectorOptions defaults)
    : pool_(pool), defaults_(std::move(defaults)) {}

grpc::ServerUnaryReactor* PerceptionServiceImpl::Detect(grpc::CallbackServerContext* context,
                                                        const v1::DetectRequest* request,
                                                        v1::DetectResponse* response) {
  grpc::ServerUnaryReactor* reactor = context->DefaultReactor();
  // context, request and response stay valid until Finish.
  pool_->Submit([this, context, request, response, reactor] {
    reactor->Finish(RunDetect(*context, *request, defaults_, *response));
  });
  return reactor;
}

grpc::ServerUnaryReactor* PerceptionServiceImpl::ListSources(
    grpc::CallbackServerContext* context, const v1::ListSourcesRequest* /*request*/,
    v1::ListSourcesResponse* /*response*/) {
  // No frame sources are configured in this version: an empty list.
  grpc::ServerUnaryReactor* reactor = context->DefaultReactor();
  reactor->Finish(grpc::Status::OK);
  return reactor;
}

}  // namespace cornerpose::server
