#include "server/metrics/server_metrics.h"

#include <grpcpp/support/interceptor.h>
#include <grpcpp/support/status.h>

#include <chrono>

#include "absl/strings/str_cat.h"
#include "cornerpose/v1/perception_service.pb.h"

namespace cornerpose::server {
namespace {

using grpc::experimental::InterceptionHookPoints;

// The method's last path element: "/cornerpose.v1.PerceptionService/Detect" -> "Detect".
std::string ShortMethod(const char* full) {
  const std::string method = full != nullptr ? full : "";
  const size_t slash = method.rfind('/');
  return slash == std::string::npos ? method : method.substr(slash + 1);
}

class RpcMetricsInterceptor final : public grpc::experimental::Interceptor {
 public:
  RpcMetricsInterceptor(ServerMetrics* metrics, std::string method)
      : metrics_(metrics), method_(std::move(method)),
        detects_(method_ == "Detect" || method_ == "StreamDetections"),
        start_(std::chrono::steady_clock::now()) {
    metrics_->RpcStarted(method_);
  }
  ~RpcMetricsInterceptor() override {
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    metrics_->RpcFinished(method_, code_, seconds);
  }

  void Intercept(grpc::experimental::InterceptorBatchMethods* methods) override {
    if (detects_ && methods->QueryInterceptionHookPoint(InterceptionHookPoints::PRE_SEND_MESSAGE)) {
      // Every DetectResponse is one detection; its timings are the stages'.
      const auto* response = static_cast<const v1::DetectResponse*>(methods->GetSendMessage());
      StageTimings t;
      if (response != nullptr) {
        const v1::StageTimings& p = response->timings();
        t = {p.preprocess_ms(), p.edge_points_ms(), p.edge_segments_ms(),
             p.clubbing_ms(),   p.poses_ms(),       p.total_ms()};
      }
      metrics_->ObserveDetection("rpc", t);
    }
    if (methods->QueryInterceptionHookPoint(InterceptionHookPoints::PRE_SEND_STATUS)) {
      code_ = GrpcCodeName(methods->GetSendStatus().error_code());
    }
    methods->Proceed();
  }

 private:
  ServerMetrics* const metrics_;
  const std::string method_;
  const bool detects_;
  const std::chrono::steady_clock::time_point start_;
  // An RPC ended without a status sent (the client went away).
  std::string code_ = "CANCELLED";
};

class RpcMetricsFactory final : public grpc::experimental::ServerInterceptorFactoryInterface {
 public:
  explicit RpcMetricsFactory(ServerMetrics* metrics) : metrics_(metrics) {}
  grpc::experimental::Interceptor* CreateServerInterceptor(
      grpc::experimental::ServerRpcInfo* info) override {
    return new RpcMetricsInterceptor(metrics_, ShortMethod(info->method()));
  }

 private:
  ServerMetrics* const metrics_;
};

template <typename T>
T* Must(absl::StatusOr<T*> family) {
  // The names are constants here: a failure is a programming error.
  if (!family.ok()) {
    std::fprintf(stderr, "ServerMetrics: %s\n", family.status().ToString().c_str());
    std::abort();
  }
  return *family;
}

}  // namespace

std::string GrpcCodeName(int code) {
  static const char* const kNames[] = {
      "OK",           "CANCELLED",         "UNKNOWN",        "INVALID_ARGUMENT",
      "DEADLINE_EXCEEDED", "NOT_FOUND",    "ALREADY_EXISTS", "PERMISSION_DENIED",
      "RESOURCE_EXHAUSTED", "FAILED_PRECONDITION", "ABORTED", "OUT_OF_RANGE",
      "UNIMPLEMENTED", "INTERNAL",         "UNAVAILABLE",    "DATA_LOSS",
      "UNAUTHENTICATED"};
  if (code >= 0 && code < static_cast<int>(std::size(kNames))) return kNames[code];
  return absl::StrCat("CODE_", code);
}

ServerMetrics::ServerMetrics() {
  detections_ = Must(registry_.AddCounter(
      "cornerpose_detections_total",
      "Detections run: origin rpc (Detect, StreamDetections) or view (the web view)",
      {"origin"}));
  stage_seconds_ = Must(registry_.AddHistogram(
      "cornerpose_detection_stage_seconds", "Time of each detector stage and of the whole detection",
      {"stage"}, metrics::DefaultSecondsBuckets()));
  rpcs_ = Must(registry_.AddCounter("cornerpose_rpcs_total",
                                    "RPCs finished, by method and gRPC status code",
                                    {"method", "code"}));
  rpc_seconds_ = Must(registry_.AddHistogram(
      "cornerpose_rpc_duration_seconds",
      "RPC time from arrival to its status, queueing included (a stream's whole life)",
      {"method"}, metrics::DefaultSecondsBuckets()));
  rpcs_open_ = Must(registry_.AddGauge(
      "cornerpose_rpcs_open", "RPCs in progress by method (StreamDetections: open streams)",
      {"method"}));
  http_requests_ = Must(registry_.AddCounter(
      "cornerpose_http_requests_total", "HTTP requests answered, by route and status",
      {"route", "status"}));
  event_streams_ = Must(registry_.AddGauge("cornerpose_http_event_streams_open",
                                           "Open server-sent event streams of the web view"));
  // Present from the start, so rate() has a series before the first one.
  rpcs_open_->WithLabels({"StreamDetections"});
  rpcs_open_->WithLabels({"Detect"});
  detections_->WithLabels({"rpc"});
  detections_->WithLabels({"view"});
  event_streams_->WithLabels({});
}

void ServerMetrics::ObserveDetection(const std::string& origin, const StageTimings& t) {
  detections_->WithLabels({origin}).Increment();
  const std::pair<const char*, double> stages[] = {
      {"preprocess", t.preprocess_ms}, {"edge_points", t.edge_points_ms},
      {"edge_segments", t.edge_segments_ms}, {"clubbing", t.clubbing_ms},
      {"poses", t.poses_ms}, {"total", t.total_ms}};
  for (const auto& [stage, ms] : stages) stage_seconds_->WithLabels({stage}).Observe(ms / 1000.0);
}

void ServerMetrics::RpcStarted(const std::string& method) {
  rpcs_open_->WithLabels({method}).Add(1);
}

void ServerMetrics::RpcFinished(const std::string& method, const std::string& code,
                                double seconds) {
  rpcs_open_->WithLabels({method}).Add(-1);
  rpcs_->WithLabels({method, code}).Increment();
  rpc_seconds_->WithLabels({method}).Observe(seconds);
}

void ServerMetrics::HttpAnswered(const std::string& route, int status) {
  http_requests_->WithLabels({route, absl::StrCat(status)}).Increment();
}

void ServerMetrics::EventStreamsAdd(int delta) { event_streams_->WithLabels({}).Add(delta); }

std::unique_ptr<grpc::experimental::ServerInterceptorFactoryInterface>
ServerMetrics::MakeInterceptorFactory() {
  return std::make_unique<RpcMetricsFactory>(this);
}

}  // namespace cornerpose::server
