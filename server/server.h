// Starting and stopping a cornerpose server in-process: what main runs, and
// what the tests run on 127.0.0.1:0.
#pragma once

#include <grpcpp/server.h>

#include <memory>
#include <string>

#include "absl/status/statusor.h"
#include "server/config/server_options.h"
#include "server/service/detection_pool.h"
#include "server/service/perception_service.h"

namespace cornerpose::server {

// A server that is listening. Destroying it shuts it down.
class RunningServer {
 public:
  RunningServer(std::unique_ptr<DetectionPool> pool, std::unique_ptr<PerceptionServiceImpl> service,
                std::unique_ptr<grpc::Server> server, int port);
  ~RunningServer();

  RunningServer(const RunningServer&) = delete;
  RunningServer& operator=(const RunningServer&) = delete;

  // The port bound (the chosen one when the address asked for port 0).
  int port() const { return port_; }
  grpc::Server& grpc_server() { return *server_; }

  // Stops accepting RPCs and waits for those in flight. Idempotent.
  void Shutdown();
  // Blocks until Shutdown is called (from another thread).
  void Wait();

 private:
  // Destroyed in reverse order: the server (already shut down) before the
  // service it calls, and both before the pool the service submits to.
  std::unique_ptr<DetectionPool> pool_;
  std::unique_ptr<PerceptionServiceImpl> service_;
  std::unique_ptr<grpc::Server> server_;
  int port_;
  bool shut_down_ = false;
};

// Binds options.listen_address with health checking and reflection enabled.
// INVALID_ARGUMENT for bad options; UNAVAILABLE when the address cannot be
// bound.
absl::StatusOr<std::unique_ptr<RunningServer>> StartServer(const ServerOptions& options);

}  // namespace cornerpose::server
