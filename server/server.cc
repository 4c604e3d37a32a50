#include "server/server.h"

#include <grpcpp/health_check_service_interface.h>
#include <grpcpp/server_builder.h>

#include <algorithm>
#include <chrono>
#include <limits>
#include <mutex>
#include <set>
#include <utility>

#include "absl/strings/str_cat.h"
#include "common/grpc_security/reflection.h"
#include "common/grpc_security/tls.h"
#include "server/sources/source_factory.h"

namespace cornerpose::server {

RunningServer::RunningServer(const ServerOptions& options, std::unique_ptr<DetectionPool> pool,
                             std::unique_ptr<PerceptionServiceImpl> service,
                             std::unique_ptr<grpc::Server> server, int port,
                             std::unique_ptr<ServerMetrics> metrics,
                             std::unique_ptr<HttpServer> http)
    : shutdown_grace_ms_(options.shutdown_grace_ms),
      stall_timeout_ms_(options.stall_timeout_ms),
      pool_(std::move(pool)),
      metrics_(std::move(metrics)),
      service_(std::move(service)),
      server_(std::move(server)),
      http_(std::move(http)),
      port_(port) {
  watchdog_ = std::thread([this] { WatchPool(); });
}

RunningServer::~RunningServer() { Shutdown(); }

void RunningServer::WatchPool() {
  const std::chrono::milliseconds limit(stall_timeout_ms_);
  // Often enough to flip within a fraction of the limit, never busy.
  const std::chrono::milliseconds period(std::clamp(stall_timeout_ms_ / 4, 5, 1000));
  bool serving = true;
  std::unique_lock<std::mutex> lock(mutex_);
  while (!stop_watch_.wait_for(lock, period, [this] { return shut_down_; })) {
    const bool stalled = pool_->Stalled(limit);
    if (stalled == !serving) continue;
    serving = !stalled;
    // Both the server as a whole ("") and each service.
    server_->GetHealthCheckService()->SetServingStatus(serving);
  }
}

void RunningServer::Shutdown() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (shut_down_) return;
    shut_down_ = true;
  }
  stop_watch_.notify_all();
  watchdog_.join();
  if (http_ != nullptr) http_->Shutdown();
  service_->StopStreams();
  // gRPC sets health NOT_SERVING, refuses new calls and cancels those still
  // running at the deadline; queued detections of cancelled calls then end
  // at their next check instead of running.
  server_->Shutdown(std::chrono::system_clock::now() +
                    std::chrono::milliseconds(shutdown_grace_ms_));
  // Handlers of cancelled calls may still be on their way out; the service
  // and the pool they use must outlive them.
  while (service_->open_streams() > 0) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  pool_->WaitIdle();
}

void RunningServer::Wait() { server_->Wait(); }

absl::StatusOr<std::unique_ptr<RunningServer>> StartServer(const ServerOptions& options) {
  if (absl::Status s = options.Validate(); !s.ok()) return s;

  std::set<std::string> names;
  for (const SourceSpec& spec : options.sources) {
    if (spec.name.empty()) return absl::InvalidArgumentError("a source has an empty name");
    if (!names.insert(spec.name).second) {
      return absl::InvalidArgumentError(absl::StrCat("source '", spec.name, "' given twice"));
    }
    if (!(spec.fps > 0)) {
      return absl::InvalidArgumentError(
          absl::StrCat("source '", spec.name, "': fps ", spec.fps, " must be > 0"));
    }
  }
  absl::StatusOr<std::shared_ptr<grpc::ServerCredentials>> credentials = MakeServerCredentials(
      {.cert = options.tls_cert, .key = options.tls_key, .client_ca = options.tls_client_ca});
  if (!credentials.ok()) return credentials.status();

  // A process-wide switch read when a ServerBuilder is made.
  static std::once_flag once;
  std::call_once(once, [] { grpc::EnableDefaultHealthCheckService(true); });

  if (!options.http.listen_address.empty()) {
    if (absl::Status s = options.http.Validate(); !s.ok()) return s;
  }

  auto pool = std::make_unique<DetectionPool>(options.max_concurrent_detections,
                                              options.max_queued_detections);
  auto metrics = std::make_unique<ServerMetrics>();
  DetectionPool* pool_ptr = pool.get();
  if (absl::Status s = metrics->registry().AddGaugeCallback(
          "cornerpose_detection_queue_depth", "Detections waiting for a worker", {},
          [pool_ptr] {
            return std::vector<std::pair<cornerpose::metrics::LabelValues, double>>{
                {{}, static_cast<double>(pool_ptr->queue_depth())}};
          });
      !s.ok()) {
    return s;
  }
  // Started before the server so the first frames are loading while it
  // binds; a source that fails is listed as FAILED rather than refusing to
  // start (one bad recording should not take down the others).
  std::vector<std::unique_ptr<FrameSource>> sources = MakeFrameSources(options.sources);
  auto service = std::make_unique<PerceptionServiceImpl>(
      pool.get(), options.detector, std::move(sources), options.box_models,
      ServiceLimits{.max_streams = options.max_streams,
                    .default_deadline = absl::Milliseconds(options.default_deadline_ms),
                    .max_deadline = absl::Milliseconds(options.max_deadline_ms),
                    .carry_unchanged_frames = options.carry_unchanged_frames});

  grpc::ServerBuilder builder;
  ConfigureReflection(builder, options.enable_reflection);
  int port = 0;
  builder.AddListeningPort(options.listen_address, *credentials, &port);
  builder.SetMaxReceiveMessageSize(options.max_message_bytes);
  builder.SetMaxSendMessageSize(options.max_message_bytes);
  if (options.max_connection_age_s > 0) {
    builder.AddChannelArgument(GRPC_ARG_MAX_CONNECTION_AGE_MS, options.max_connection_age_s * 1000);
    // Let open streams finish however long they run.
    builder.AddChannelArgument(GRPC_ARG_MAX_CONNECTION_AGE_GRACE_MS,
                               std::numeric_limits<int>::max());
  }
  builder.RegisterService(service.get());
  std::vector<std::unique_ptr<grpc::experimental::ServerInterceptorFactoryInterface>> interceptors;
  interceptors.push_back(metrics->MakeInterceptorFactory());
  builder.experimental().SetInterceptorCreators(std::move(interceptors));
  std::unique_ptr<grpc::Server> server = builder.BuildAndStart();
  if (server == nullptr || port == 0) {
    if (server != nullptr) server->Shutdown();
    return absl::UnavailableError(absl::StrCat("could not listen on '", options.listen_address,
                                               "' (address in use or malformed?)"));
  }
  // Known by name too, so a probe asking for the service gets its status
  // (and the watchdog's SetServingStatus(bool) flips it with "").
  server->GetHealthCheckService()->SetServingStatus(v1::PerceptionService::service_full_name(),
                                                    true);
  std::unique_ptr<HttpServer> http;
  if (!options.http.listen_address.empty()) {
    // The gRPC port's certificate serves HTTPS too (plaintext when none).
    absl::StatusOr<std::unique_ptr<HttpServer>> started = HttpServer::Start(
        options.http, HttpTls{.cert_file = options.tls_cert, .key_file = options.tls_key},
        service->sources(), pool.get(), options.detector, &service->box_models(), metrics.get());
    if (!started.ok()) {
      server->Shutdown();
      return started.status();
    }
    http = *std::move(started);
  }
  return std::make_unique<RunningServer>(options, std::move(pool), std::move(service),
                                         std::move(server), port, std::move(metrics),
                                         std::move(http));
}

}  // namespace cornerpose::server
