#include "server/service/perception_service.h"

#include <algorithm>
#include <chrono>
#include <map>
#include <optional>
#include <string>
#include <utility>

#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"
#include "common/validation/range_check.h"
#include "server/service/detect_request.h"
#include "server/service/detect_response.h"
#include "server/service/status_mapping.h"
#include "server/service/stream_detections.h"

namespace cornerpose::server {
namespace {

// OK while the caller still wants the answer. Checked before and after the
// detector (which cannot be interrupted), so a request that waited in the
// queue past its deadline costs no detection, and a late one no conversion.
grpc::Status CheckStillWanted(grpc::CallbackServerContext& context, absl::Time deadline) {
  if (deadline <= absl::Now()) {
    return grpc::Status(grpc::StatusCode::DEADLINE_EXCEEDED, "deadline exceeded");
  }
  if (context.IsCancelled()) return grpc::Status(grpc::StatusCode::CANCELLED, "cancelled");
  return grpc::Status::OK;
}

// The longest a Detect waits for a source's first frame (a replay starting,
// a camera warming up); also capped by the caller's deadline. It blocks a pool
// worker meanwhile, so it is short.
constexpr absl::Duration kMaxFrameWait = absl::Seconds(2);

v1::SourceState ToProto(SourceState state) {
  switch (state) {
    case SourceState::kStarting:
      return v1::SOURCE_STATE_STARTING;
    case SourceState::kRunning:
      return v1::SOURCE_STATE_RUNNING;
    case SourceState::kFailed:
      return v1::SOURCE_STATE_FAILED;
    case SourceState::kFinished:
      return v1::SOURCE_STATE_FINISHED;
  }
  return v1::SOURCE_STATE_UNSPECIFIED;
}

// The newest frame of the named source. NOT_FOUND for an unknown name;
// UNAVAILABLE when the source failed or has no frame in time.
absl::StatusOr<Frame> GrabFromSource(
    const std::map<std::string, std::unique_ptr<FrameSource>>& sources, const std::string& name,
    absl::Time deadline) {
  auto it = sources.find(name);
  if (it == sources.end()) {
    return absl::NotFoundError(absl::StrCat("unknown source ", QuotedName(name)));
  }
  const absl::Duration until_deadline = deadline - absl::Now();
  return it->second->Grab(std::min(kMaxFrameWait, until_deadline));
}

// The caller's deadline capped at limits.max_deadline, or
// limits.default_deadline when the caller set none.
absl::Time EffectiveDeadline(const grpc::CallbackServerContext& context,
                             const ServiceLimits& limits) {
  const absl::Time now = absl::Now();
  // gRPC reports "no deadline" as the far future.
  if (context.deadline() >= std::chrono::system_clock::now() + std::chrono::hours(24 * 365 * 100)) {
    return now + limits.default_deadline;
  }
  return std::min(absl::FromChrono(context.deadline()), now + limits.max_deadline);
}

grpc::Status RunDetect(grpc::CallbackServerContext& context, absl::Time deadline,
                       const v1::DetectRequest& request, const DetectorOptions& defaults,
                       const BoxModels& box_models,
                       const std::map<std::string, std::unique_ptr<FrameSource>>& sources,
                       CarriedDetections& carried, v1::DetectResponse& response) {
  if (grpc::Status s = CheckStillWanted(context, deadline); !s.ok()) return s;
  absl::StatusOr<DetectorOptions> options =
      DetectorOptionsFromRequest(request, defaults, box_models);
  if (!options.ok()) return ToGrpcStatus(options.status());
  std::shared_ptr<const Frame> frame;
  std::string carry_key;  // the source and the parameters that change the detection
  const ResponseContents contents{.include_edge_points = request.include_edge_points(),
                                  .include_cloud = request.include_cloud()};
  absl::StatusOr<PointCloud> sent;
  const PointCloud* cloud = nullptr;
  if (request.input_case() == v1::DetectRequest::kSource) {
    if (request.has_color()) {
      return ToGrpcStatus(absl::InvalidArgumentError(
          "color is for a cloud or depth_image sent with the request; a source's frames bring "
          "their own"));
    }
    absl::StatusOr<Frame> grabbed = GrabFromSource(sources, request.source(), deadline);
    if (!grabbed.ok()) return ToGrpcStatus(grabbed.status());
    frame = std::make_shared<const Frame>(*std::move(grabbed));
    cloud = &frame->cloud;
    // The source knows its camera; the request's intrinsics do not apply.
    UseFrameCamera(frame->camera, &*options);
    // The same scene as the last call's frame: its detection, at once.
    v1::DetectRequest parameters = request;
    parameters.clear_include_edge_points();
    parameters.clear_include_cloud();
    carry_key = parameters.SerializeAsString();
    if (std::optional<CarriedDetections::Carried> c = carried.Find(carry_key, *frame, *options)) {
      if (grpc::Status s = CheckStillWanted(context, deadline); !s.ok()) return s;
      response = MakeDetectResponse(*c->detection, *options, frame.get(), contents);
      response.set_detected_frame_id(c->frame_id);
      return grpc::Status::OK;
    }
  } else {
    sent = CloudFromRequest(request);
    if (!sent.ok()) return ToGrpcStatus(sent.status());
    cloud = &*sent;
  }
  if (grpc::Status s = CheckStillWanted(context, deadline); !s.ok()) return s;

  // The detector itself stops when the deadline passes or the caller goes
  // away, so an abandoned call frees its worker within milliseconds.
  const CancelToken cancel(deadline, [&context] { return context.IsCancelled(); });
  absl::StatusOr<Detection> detection = DetectBoxes(*cloud, *options, cancel);
  if (!detection.ok()) return ToGrpcStatus(detection.status());
  if (frame != nullptr) carried.Store(carry_key, frame, *detection);

  if (grpc::Status s = CheckStillWanted(context, deadline); !s.ok()) return s;
  response = MakeDetectResponse(*detection, *options, frame.get(), contents);
  return grpc::Status::OK;
}

}  // namespace

PerceptionServiceImpl::PerceptionServiceImpl(DetectionPool* pool, const DetectorOptions& defaults,
                                             std::vector<std::unique_ptr<FrameSource>> sources,
                                             BoxModels box_models, ServiceLimits limits)
    : pool_(pool),
      defaults_(defaults),
      box_models_(std::move(box_models)),
      limits_(limits),
      shared_(limits.carry_unchanged_frames),
      carried_(limits.carry_unchanged_frames) {
  for (std::unique_ptr<FrameSource>& source : sources) {
    const std::string name = source->name();
    sources_.emplace(name, std::move(source));
  }
}

grpc::ServerUnaryReactor* PerceptionServiceImpl::Detect(grpc::CallbackServerContext* context,
                                                        const v1::DetectRequest* request,
                                                        v1::DetectResponse* response) {
  grpc::ServerUnaryReactor* reactor = context->DefaultReactor();
  // A bad box or override is refused before it can take a queue slot (cheap;
  // the cloud itself is checked on the worker).
  if (absl::StatusOr<DetectorOptions> options =
          DetectorOptionsFromRequest(*request, defaults_, box_models_);
      !options.ok()) {
    reactor->Finish(ToGrpcStatus(options.status()));
    return reactor;
  }
  const absl::Time deadline = EffectiveDeadline(*context, limits_);
  // context, request and response stay valid until Finish.
  const bool queued = pool_->TrySubmit([this, context, deadline, request, response, reactor] {
    reactor->Finish(RunDetect(*context, deadline, *request, defaults_, box_models_, sources_,
                              carried_, *response));
  });
  if (!queued) {
    // Refused at once, so a client can back off or try another replica.
    reactor->Finish(grpc::Status(grpc::StatusCode::RESOURCE_EXHAUSTED,
                                 "detection queue full; retry later or on another replica"));
  }
  return reactor;
}

grpc::ServerUnaryReactor* PerceptionServiceImpl::ListSources(
    grpc::CallbackServerContext* context, const v1::ListSourcesRequest* /*request*/,
    v1::ListSourcesResponse* response) {
  // Cheap (a lock per source), so answered on the callback thread.
  for (const auto& [name, source] : sources_) {
    v1::Source* out = response->add_sources();
    out->set_name(name);
    out->set_description(source->description());
    const SourceStatus status = source->state();
    out->set_state(ToProto(status.state));
    out->set_state_reason(status.reason);
    out->set_live(source->live());
  }
  grpc::ServerUnaryReactor* reactor = context->DefaultReactor();
  reactor->Finish(grpc::Status::OK);
  return reactor;
}

}  // namespace cornerpose::server

namespace cornerpose::server {

grpc::ServerWriteReactor<v1::DetectResponse>* PerceptionServiceImpl::StreamDetections(
    grpc::CallbackServerContext* /*context*/, const v1::StreamDetectionsRequest* request) {
  if (open_streams_.fetch_add(1) >= limits_.max_streams) {
    open_streams_.fetch_sub(1);
    return new StreamDetectionsReactor(grpc::Status(
        grpc::StatusCode::RESOURCE_EXHAUSTED,
        absl::StrCat("too many open streams (max_streams ", limits_.max_streams, ")")));
  }
  // Every early return below hands the slot back in the error reactor's
  // stead.
  const auto refuse = [this](const absl::Status& status) {
    open_streams_.fetch_sub(1);
    return new StreamDetectionsReactor(ToGrpcStatus(status));
  };
  absl::StatusOr<DetectorOptions> options =
      DetectorOptionsFromRequest(*request, defaults_, box_models_);
  if (!options.ok()) return refuse(options.status());
  auto it = sources_.find(request->source());
  if (it == sources_.end()) {
    return refuse(
        absl::NotFoundError(absl::StrCat("unknown source ", QuotedName(request->source()))));
  }
  // Streams whose requests differ only in what the response carries share
  // their detections.
  v1::StreamDetectionsRequest parameters = *request;
  parameters.clear_include_edge_points();
  parameters.clear_include_cloud();
  parameters.clear_every_frame();
  std::string share_key = parameters.SerializeAsString();
  return new StreamDetectionsReactor(pool_, &shared_, std::move(share_key), it->second.get(),
                                     *std::move(options),
                                     {.include_edge_points = request->include_edge_points(),
                                      .include_cloud = request->include_cloud()},
                                     request->every_frame(), &stopping_streams_, &open_streams_);
}

}  // namespace cornerpose::server
