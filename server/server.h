// Starting and stopping a cornerpose server in-process: what main runs, and
// what the tests run on 127.0.0.1:0.
#pragma once

#include <grpcpp/server.h>

#include <condition_variable>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "absl/status/statusor.h"
#include "server/config/server_options.h"
#include "server/http/http_server.h"
#include "server/metrics/server_metrics.h"
#include "server/service/detection_pool.h"
#include "server/service/perception_service.h"

namespace cornerpose::server {

// A server that is listening. Destroying it shuts it down.
class RunningServer {
 public:
  RunningServer(const ServerOptions& options, std::unique_ptr<DetectionPool> pool,
                std::unique_ptr<PerceptionServiceImpl> service,
                std::unique_ptr<grpc::Server> server, int port,
                std::unique_ptr<ServerMetrics> metrics = nullptr,
                std::unique_ptr<HttpServer> http = nullptr);
  ~RunningServer();

  RunningServer(const RunningServer&) = delete;
  RunningServer& operator=(const RunningServer&) = delete;

  // The port bound (the chosen one when the address asked for port 0).
  int port() const { return port_; }
  grpc::Server& grpc_server() { return *server_; }
  // The HTTP port bound (web view, JSON API, /metrics); 0 when it is off.
  int http_port() const { return http_ != nullptr ? http_->port() : 0; }
  // The detection pool and the service, for diagnostics and tests (the
  // admission tests occupy the real pool to fill it or wedge it).
  DetectionPool& pool() { return *pool_; }
  const PerceptionServiceImpl& service() const { return *service_; }

  // Health NOT_SERVING, open streams ended (UNAVAILABLE), no new RPCs; RPCs in
  // flight get options.shutdown_grace_ms to finish, then are cancelled.
  // Returns once every RPC is done. Idempotent.
  void Shutdown();
  // Blocks until Shutdown is called (from another thread).
  void Wait();

 private:
  // Sets health NOT_SERVING while the pool is stalled, SERVING when it moves.
  void WatchPool();

  const int shutdown_grace_ms_;
  const int stall_timeout_ms_;
  // Destroyed in reverse order: the server (already shut down) before the
  // service it calls, and both before the pool the service submits to.
  // The metrics before the servers that count into them; the HTTP port
  // (whose views use the pool and the sources) first of all.
  std::unique_ptr<DetectionPool> pool_;
  std::unique_ptr<ServerMetrics> metrics_;
  std::unique_ptr<PerceptionServiceImpl> service_;
  std::unique_ptr<grpc::Server> server_;
  std::unique_ptr<HttpServer> http_;
  int port_;
  std::mutex mutex_;
  std::condition_variable stop_watch_;
  bool shut_down_ = false;  // guarded by mutex_
  std::thread watchdog_;
};

// Binds options.listen_address (TLS when options.tls_cert is set) with
// health checking and, when enabled, reflection, and options.http.listen_address
// (unless empty; HTTPS with the same certificate when TLS is on) for the web
// view and /metrics. INVALID_ARGUMENT for bad options (ServerOptions::Validate);
// NOT_FOUND for an unreadable TLS file; UNAVAILABLE when an address cannot be
// bound.
absl::StatusOr<std::unique_ptr<RunningServer>> StartServer(const ServerOptions& options);

}  // namespace cornerpose::server
