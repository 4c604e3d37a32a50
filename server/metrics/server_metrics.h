// The perception server's Prometheus metrics (GET /metrics on the HTTP
// port): detections and their per-stage latency, RPCs by method and status
// code with their latency, RPCs and streams open, the detection queue, and
// per source its state, frame age and frame rate. RPCs are measured by a
// gRPC server interceptor (MakeInterceptorFactory), so the handlers stay
// free of metrics code.
#pragma once

#include <grpcpp/support/server_interceptor.h>

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "common/metrics/metrics.h"
#include "common/perception/types.h"

namespace cornerpose::server {

class ServerMetrics {
 public:
  ServerMetrics();

  metrics::Registry& registry() { return registry_; }
  std::string Serialize() const { return registry_.Serialize(); }

  // One detection ran; `origin` "rpc" (Detect, StreamDetections) or "view".
  void ObserveDetection(const std::string& origin, const StageTimings& timings);
  // An RPC started / finished with gRPC status `code` ("OK", "NOT_FOUND") after `seconds`.
  void RpcStarted(const std::string& method);
  void RpcFinished(const std::string& method, const std::string& code, double seconds);
  // An HTTP request answered: its route ("/api/sources/{name}/latest") and status.
  void HttpAnswered(const std::string& route, int status);
  void EventStreamsAdd(int delta);

  // Counts every RPC of the server it is installed on; the metrics outlive it.
  std::unique_ptr<grpc::experimental::ServerInterceptorFactoryInterface> MakeInterceptorFactory();

 private:
  metrics::Registry registry_;
  metrics::CounterFamily* detections_;
  metrics::HistogramFamily* stage_seconds_;
  metrics::CounterFamily* rpcs_;
  metrics::HistogramFamily* rpc_seconds_;
  metrics::GaugeFamily* rpcs_open_;
  metrics::CounterFamily* http_requests_;
  metrics::GaugeFamily* event_streams_;
};

// The gRPC status code's name, as grpc::StatusCode spells it ("OK", "NOT_FOUND").
std::string GrpcCodeName(int code);

}  // namespace cornerpose::server
