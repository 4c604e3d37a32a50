#include "server/server.h"

#include <grpcpp/ext/proto_server_reflection_plugin.h>
#include <grpcpp/health_check_service_interface.h>
#include <grpcpp/security/server_credentials.h>
#include <grpcpp/server_builder.h>

#include <limits>
#include <mutex>
#include <set>
#include <utility>

#include "absl/strings/str_cat.h"
#include "server/sources/source_factory.h"

namespace cornerpose::server {

RunningServer::RunningServer(std::unique_ptr<DetectionPool> pool,
                             std::unique_ptr<PerceptionServiceImpl> service,
                             std::unique_ptr<grpc::Server> server, int port)
    : pool_(std::move(pool)),
      service_(std::move(service)),
      server_(std::move(server)),
      port_(port) {}

RunningServer::~RunningServer() { Shutdown(); }

void RunningServer::Shutdown() {
  if (shut_down_) return;
  shut_down_ = true;
  service_->StopStreams();
  server_->Shutdown();
}

void RunningServer::Wait() { server_->Wait(); }

absl::StatusOr<std::unique_ptr<RunningServer>> StartServer(const ServerOptions& options) {
  if (options.max_message_bytes <= 0) {
    return absl::InvalidArgumentError(
        absl::StrCat("max_message_bytes ", options.max_message_bytes, " must be > 0"));
  }
  if (options.max_concurrent_detections < 1) {
    return absl::InvalidArgumentError(absl::StrCat(
        "max_concurrent_detections ", options.max_concurrent_detections, " must be >= 1"));
  }
  // At most a day, so the milliseconds fit gRPC's int argument.
  if (options.max_connection_age_s < 0 || options.max_connection_age_s > 86400) {
    return absl::InvalidArgumentError(absl::StrCat(
        "max_connection_age_s ", options.max_connection_age_s, " must be in [0, 86400]"));
  }

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

  // Both are process-wide switches read when a ServerBuilder is made.
  static std::once_flag once;
  std::call_once(once, [] {
    grpc::EnableDefaultHealthCheckService(true);
    grpc::reflection::InitProtoReflectionServerBuilderPlugin();
  });

  auto pool = std::make_unique<DetectionPool>(options.max_concurrent_detections);
  // Started before the server so the first frames are loading while it
  // binds; a source that fails is listed as FAILED rather than refusing to
  // start (one bad recording should not take down the others).
  std::vector<std::unique_ptr<FrameSource>> sources = MakeFrameSources(options.sources);
  auto service = std::make_unique<PerceptionServiceImpl>(pool.get(), options.detector,
                                                         std::move(sources), options.box_models);

  grpc::ServerBuilder builder;
  int port = 0;
  builder.AddListeningPort(options.listen_address, grpc::InsecureServerCredentials(), &port);
  builder.SetMaxReceiveMessageSize(options.max_message_bytes);
  builder.SetMaxSendMessageSize(options.max_message_bytes);
  if (options.max_connection_age_s > 0) {
    builder.AddChannelArgument(GRPC_ARG_MAX_CONNECTION_AGE_MS, options.max_connection_age_s * 1000);
    // Let open streams finish however long they run.
    builder.AddChannelArgument(GRPC_ARG_MAX_CONNECTION_AGE_GRACE_MS,
                               std::numeric_limits<int>::max());
  }
  builder.RegisterService(service.get());
  std::unique_ptr<grpc::Server> server = builder.BuildAndStart();
  if (server == nullptr || port == 0) {
    if (server != nullptr) server->Shutdown();
    return absl::UnavailableError(absl::StrCat("could not listen on '", options.listen_address,
                                               "' (address in use or malformed?)"));
  }
  return std::make_unique<RunningServer>(std::move(pool), std::move(service), std::move(server),
                                         port);
}

}  // namespace cornerpose::server
