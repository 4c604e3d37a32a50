// The server's HTTP port: the web view's files (web/, embedded), its JSON
// API and server-sent events (web/README.md), and /metrics. cpp-httplib
// (Debian's libcpp-httplib-dev) runs it on its own thread pool, apart from
// gRPC's threads; detections go to the server's DetectionPool.
#pragma once

#include <atomic>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "absl/status/statusor.h"
#include "common/box/box_models.h"
#include "common/perception/detector.h"
#include "server/http/cell_status_client.h"
#include "server/http/http_options.h"
#include "server/http/source_view.h"
#include "server/metrics/server_metrics.h"
#include "server/service/detection_pool.h"
#include "server/sources/frame_source.h"

namespace httplib {
class Server;
}

namespace cornerpose::server {

// PEM files for HTTPS; both empty = plain HTTP.
struct HttpTls {
  std::string cert_file;
  std::string key_file;
};

class HttpServer {
 public:
  ~HttpServer();
  HttpServer(const HttpServer&) = delete;
  HttpServer& operator=(const HttpServer&) = delete;

  // Listens on options.listen_address (not empty). Everything pointed to
  // outlives the server. INVALID_ARGUMENT for bad options or an unknown
  // view_box; UNAVAILABLE when the address cannot be bound or the TLS files
  // cannot be read.
  static absl::StatusOr<std::unique_ptr<HttpServer>> Start(
      const HttpOptions& options, const HttpTls& tls, const std::vector<FrameSource*>& sources,
      DetectionPool* pool, const DetectorOptions& defaults, const BoxModels* box_models,
      ServerMetrics* metrics);

  int port() const { return port_; }
  // Ends the event streams, stops listening, stops the views. Idempotent.
  void Shutdown();

 private:
  HttpServer() = default;
  void AddRoutes();
  // Per-source gauges (state, frame age, frame rate) read from the views.
  absl::Status AddSourceMetrics(ServerMetrics* metrics);
  SourceView* FindView(const std::string& name) const;

  HttpOptions options_;
  ServerMetrics* metrics_ = nullptr;
  std::unique_ptr<CellStatusClient> cell_;
  std::vector<std::unique_ptr<SourceView>> views_;
  std::unique_ptr<httplib::Server> http_;
  std::thread thread_;
  int port_ = 0;
  std::atomic<bool> stopping_{false};
};

}  // namespace cornerpose::server
