// A small HTTP port that serves one Registry at /metrics (the daemon's
// metrics_listen; the server serves its metrics on its web view's port).
// cpp-httplib, as the server's HTTP port.
#pragma once

#include <memory>
#include <string>
#include <thread>

#include "absl/status/statusor.h"
#include "common/metrics/metrics.h"

namespace httplib {
class Server;
}

namespace cornerpose::metrics {

class MetricsHttpServer {
 public:
  // Listens on host:port (port 0 picks one); `registry` outlives the server.
  // INVALID_ARGUMENT for a malformed address; UNAVAILABLE when it cannot be bound.
  static absl::StatusOr<std::unique_ptr<MetricsHttpServer>> Start(const std::string& listen,
                                                                  const Registry* registry);
  ~MetricsHttpServer();
  MetricsHttpServer(const MetricsHttpServer&) = delete;
  MetricsHttpServer& operator=(const MetricsHttpServer&) = delete;

  int port() const { return port_; }
  void Shutdown();  // idempotent

 private:
  MetricsHttpServer() = default;
  std::unique_ptr<httplib::Server> http_;
  std::thread thread_;
  int port_ = 0;
};

}  // namespace cornerpose::metrics
