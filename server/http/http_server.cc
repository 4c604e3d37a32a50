#include "server/http/http_server.h"

#include <httplib.h>

#include <cmath>
#include <cstdlib>
#include <utility>

#include "absl/strings/match.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"
#include "common/validation/range_check.h"
#include "server/http/frame_encoding.h"
#include "server/http/view_json.h"
#include "web/web_assets.h"

namespace cornerpose::server {
namespace {

constexpr char kJson[] = "application/json";
// How long /latest waits for a first detection (a source starting, the
// detector queueing behind others).
constexpr absl::Duration kLatestWait = absl::Seconds(10);
// An event stream checks for shutdown, a new frame and a state change this often.
constexpr absl::Duration kEventPoll = absl::Milliseconds(500);
// A comment this often keeps proxies from closing a quiet stream.
constexpr absl::Duration kKeepAlive = absl::Seconds(15);

int HttpStatusOf(const absl::Status& status) {
  switch (status.code()) {
    case absl::StatusCode::kInvalidArgument:
      return 400;
    case absl::StatusCode::kNotFound:
      return 404;
    case absl::StatusCode::kResourceExhausted:
      return 429;
    default:
      return 503;
  }
}

void SendJson(httplib::Response& res, int status, const std::string& body) {
  res.status = status;
  res.set_header("Cache-Control", "no-store");
  res.set_content(body, kJson);
}

void SendError(httplib::Response& res, int status, const std::string& message) {
  SendJson(res, status, ErrorJson(message));
}

void SendError(httplib::Response& res, const absl::Status& status) {
  SendError(res, HttpStatusOf(status), std::string(status.message()));
}

// The route a path belongs to, for the metrics' label (bounded: no names).
std::string RouteOf(const std::string& path) {
  if (path == "/metrics" || path == "/api/sources" || path == "/api/cell") return path;
  if (absl::StartsWith(path, "/api/sources/")) {
    for (const char* tail : {"/latest", "/events", "/image.png", "/cloud.bin"}) {
      if (absl::EndsWith(path, tail)) {
        return absl::StrCat(absl::EndsWith(tail, "png") || absl::EndsWith(tail, "bin")
                                ? "/api/sources/{name}/frames/{id}"
                                : "/api/sources/{name}",
                            tail);
      }
    }
  }
  if (absl::StartsWith(path, "/assets/")) return "/assets";
  if (path == "/" || path == "/index.html" || absl::StartsWith(path, "/sources/")) return "/";
  return "other";
}

void SendAsset(httplib::Response& res, const std::string& path) {
  const web::WebAsset* asset = web::FindWebAsset(path);
  if (asset == nullptr) {
    SendError(res, 404, absl::StrCat("no file ", path));
    return;
  }
  res.set_content(std::string(asset->body), std::string(asset->content_type).c_str());
}

}  // namespace

HttpServer::~HttpServer() { Shutdown(); }

SourceView* HttpServer::FindView(const std::string& name) const {
  for (const auto& view : views_) {
    if (view->name() == name) return view.get();
  }
  return nullptr;
}

absl::StatusOr<std::unique_ptr<HttpServer>> HttpServer::Start(
    const HttpOptions& options, const HttpTls& tls, const std::vector<FrameSource*>& sources,
    DetectionPool* pool, const DetectorOptions& defaults, const BoxModels* box_models,
    ServerMetrics* metrics) {
  if (absl::Status s = options.Validate(); !s.ok()) return s;
  absl::StatusOr<BoxDims> view_box = ResolveBoxModel(options.view_box, *box_models);
  if (!view_box.ok()) view_box = ParseBoxDims(options.view_box);
  if (!view_box.ok()) {
    return absl::InvalidArgumentError(absl::StrCat("view_box '", options.view_box,
                                                   "' is neither a box model nor L,B,H in metres"));
  }
  const size_t colon = options.listen_address.rfind(':');
  int port = -1;
  if (colon == std::string::npos ||
      !absl::SimpleAtoi(options.listen_address.substr(colon + 1), &port) || port < 0 ||
      port > 65535) {
    return absl::InvalidArgumentError(absl::StrCat("http_listen '", options.listen_address,
                                                   "' is not host:port (port 0 to 65535)"));
  }
  std::string host = options.listen_address.substr(0, colon);
  // [::1]:8080 -> ::1
  if (host.size() >= 2 && host.front() == '[' && host.back() == ']') {
    host = host.substr(1, host.size() - 2);
  }
  if (tls.cert_file.empty() != tls.key_file.empty()) {
    return absl::InvalidArgumentError("HTTPS needs both a certificate and a key file");
  }

  std::unique_ptr<HttpServer> server(new HttpServer());
  server->options_ = options;
  server->metrics_ = metrics;
  if (!tls.cert_file.empty()) {
    auto https = std::make_unique<httplib::SSLServer>(tls.cert_file.c_str(), tls.key_file.c_str());
    if (!https->is_valid()) {
      return absl::UnavailableError(absl::StrCat("HTTPS: cannot use the certificate '",
                                                 tls.cert_file, "' with the key '", tls.key_file,
                                                 "'"));
    }
    server->http_ = std::move(https);
  } else {
    server->http_ = std::make_unique<httplib::Server>();
  }
  if (!options.cell_status_address.empty()) {
    absl::StatusOr<std::unique_ptr<CellStatusClient>> cell = CellStatusClient::Create(
        options.cell_status_address, {.ca = options.cell_status_tls_ca,
                                      .cert = options.cell_status_tls_cert,
                                      .key = options.cell_status_tls_key,
                                      .server_name = options.cell_status_tls_server_name});
    if (!cell.ok()) return cell.status();
    server->cell_ = *std::move(cell);
  }
  for (FrameSource* source : sources) {
    SourceView::DetectionHook hook;
    if (metrics != nullptr) {
      hook = [metrics](const Detection& d) { metrics->ObserveDetection("view", d.timings); };
    }
    server->views_.push_back(
        std::make_unique<SourceView>(source, pool, defaults, box_models, options, hook));
  }
  if (metrics != nullptr) {
    if (absl::Status s = server->AddSourceMetrics(metrics); !s.ok()) return s;
  }
  const int threads = options.num_threads;
  server->http_->new_task_queue = [threads] { return new httplib::ThreadPool(threads); };
  server->AddRoutes();
  if (port == 0) {
    server->port_ = server->http_->bind_to_any_port(host);
  } else if (server->http_->bind_to_port(host, port)) {
    server->port_ = port;
  }
  if (server->port_ <= 0) {
    return absl::UnavailableError(absl::StrCat("could not listen on '", options.listen_address,
                                               "' for HTTP (address in use or malformed?)"));
  }
  httplib::Server* http = server->http_.get();
  server->thread_ = std::thread([http] { http->listen_after_bind(); });
  return server;
}

absl::Status HttpServer::AddSourceMetrics(ServerMetrics* metrics) {
  using Samples = std::vector<std::pair<metrics::LabelValues, double>>;
  metrics::Registry& registry = metrics->registry();
  if (absl::Status s = registry.AddGaugeCallback(
          "cornerpose_source_state",
          "1 for a source's current state (STARTING, RUNNING, FAILED, FINISHED), 0 for the others",
          {"source", "state"},
          [this] {
            Samples out;
            for (const auto& view : views_) {
              const SourceState now = view->Summary().status.state;
              for (SourceState s : {SourceState::kStarting, SourceState::kRunning,
                                    SourceState::kFailed, SourceState::kFinished}) {
                out.push_back({{view->name(), SourceStateName(s)}, s == now ? 1.0 : 0.0});
              }
            }
            return out;
          });
      !s.ok()) {
    return s;
  }
  if (absl::Status s = registry.AddGaugeCallback(
          "cornerpose_source_frame_age_seconds",
          "Seconds since the newest frame of a source was captured (NaN before the first)",
          {"source"},
          [this] {
            Samples out;
            for (const auto& view : views_) {
              const SourceSummary summary = view->Summary();
              out.push_back({{view->name()}, summary.frame_age_s.value_or(std::nan(""))});
            }
            return out;
          });
      !s.ok()) {
    return s;
  }
  return registry.AddGaugeCallback("cornerpose_source_frames_per_second",
                                   "Frames a source delivered per second over the last 5 s",
                                   {"source"}, [this] {
                                     Samples out;
                                     for (const auto& view : views_) {
                                       out.push_back({{view->name()}, view->Summary().fps});
                                     }
                                     return out;
                                   });
}

void HttpServer::Shutdown() {
  if (stopping_.exchange(true)) return;
  // Event streams see stopping_ within kEventPoll; stop() then waits for them.
  if (http_ != nullptr) http_->stop();
  if (thread_.joinable()) thread_.join();
  for (auto& view : views_) view->Stop();
}

void HttpServer::AddRoutes() {
  httplib::Server& http = *http_;
  http.set_logger([this](const httplib::Request& req, const httplib::Response& res) {
    if (metrics_ != nullptr) metrics_->HttpAnswered(RouteOf(req.path), res.status);
  });
  http.set_error_handler([](const httplib::Request& req, httplib::Response& res) {
    if (res.body.empty()) {
      res.set_content(ErrorJson(absl::StrCat("no such page ", req.path)), kJson);
    }
  });

  // The page: the same index.html for the overview and every source.
  const auto page = [](const httplib::Request&, httplib::Response& res) {
    SendAsset(res, "/index.html");
  };
  http.Get("/", page);
  http.Get("/index.html", page);
  http.Get(R"(/sources/[^/]+/?)", page);
  http.Get(R"(/assets/.+)",
           [](const httplib::Request& req, httplib::Response& res) { SendAsset(res, req.path); });

  http.Get("/metrics", [this](const httplib::Request&, httplib::Response& res) {
    if (metrics_ == nullptr) {
      SendError(res, 404, "metrics are off");
      return;
    }
    res.set_content(metrics_->Serialize(), metrics::kTextFormatContentType);
  });

  http.Get("/api/sources", [this](const httplib::Request&, httplib::Response& res) {
    std::vector<SourceSummary> summaries;
    for (const auto& view : views_) summaries.push_back(view->Summary());
    SendJson(res, 200, SourceListJson(summaries));
  });

  http.Get("/api/cell", [this](const httplib::Request&, httplib::Response& res) {
    SendJson(res, 200, cell_ != nullptr ? cell_->StatusJson() : R"({"configured":false})");
  });

  http.Get(R"(/api/sources/([^/]+)/latest)", [this](const httplib::Request& req,
                                                    httplib::Response& res) {
    SourceView* view = FindView(req.matches[1]);
    if (view == nullptr) {
      SendError(res, 404, absl::StrCat("unknown source ", QuotedName(req.matches[1].str())));
      return;
    }
    absl::StatusOr<std::shared_ptr<const ViewDetection>> d =
        view->NextDetection(req.get_param_value("box"), 0, kLatestWait);
    if (!d.ok()) {
      SendError(res, d.status());
      return;
    }
    SendJson(res, 200, ViewDetectionJson(**d));
  });

  http.Get(R"(/api/sources/([^/]+)/frames/(\d+)/(image\.png|cloud\.bin))",
           [this](const httplib::Request& req, httplib::Response& res) {
             SourceView* view = FindView(req.matches[1]);
             uint64_t id = 0;
             std::shared_ptr<const Frame> frame;
             if (view != nullptr && absl::SimpleAtoi(req.matches[2].str(), &id)) {
               frame = view->FindFrame(id);
             }
             if (frame == nullptr) {
               SendError(res, 404,
                         absl::StrCat("source '", req.matches[1].str(), "' keeps no frame ",
                                      req.matches[2].str()));
               return;
             }
             // A frame never changes: the browser may keep it.
             res.set_header("Cache-Control", "max-age=300, immutable");
             if (req.matches[3] == "image.png") {
               res.set_content(FramePng(*frame, FrameImageCamera(*frame, std::nullopt)),
                               "image/png");
             } else {
               res.set_content(FrameCloudBin(*frame), "application/octet-stream");
             }
           });

  http.Get(R"(/api/sources/([^/]+)/events)", [this](const httplib::Request& req,
                                                    httplib::Response& res) {
    SourceView* view = FindView(req.matches[1]);
    if (view == nullptr) {
      SendError(res, 404, absl::StrCat("unknown source ", QuotedName(req.matches[1].str())));
      return;
    }
    const std::string box = req.get_param_value("box");
    if (absl::Status s = view->Watch(box, +1); !s.ok()) {
      SendError(res, s);
      return;
    }
    if (metrics_ != nullptr) metrics_->EventStreamsAdd(+1);
    struct Stream {
      uint64_t last_id = 0;
      std::string last_state;
      absl::Time last_write = absl::Now();
    };
    auto stream = std::make_shared<Stream>();
    res.set_header("Cache-Control", "no-store");
    // Tells nginx not to buffer the stream.
    res.set_header("X-Accel-Buffering", "no");
    res.set_chunked_content_provider(
        "text/event-stream",
        [this, view, box, stream](size_t /*offset*/, httplib::DataSink& sink) {
          if (stopping_) return false;
          std::string out;
          // A state event (the source's summary) when its state changes.
          const SourceSummary summary = view->Summary();
          const std::string state_key =
              absl::StrCat(SourceStateName(summary.status.state), ":", summary.status.reason);
          if (state_key != stream->last_state) {
            stream->last_state = state_key;
            absl::StrAppend(&out, "event: state\ndata: ", SourceSummaryJson(summary), "\n\n");
          }
          const absl::Time asked = absl::Now();
          absl::StatusOr<std::shared_ptr<const ViewDetection>> d =
              view->NextDetection(box, stream->last_id, kEventPoll);
          // A failed source answers at once: pace the loop (httplib calls
          // the provider again as soon as it returns).
          if (!d.ok()) absl::SleepFor(kEventPoll - (absl::Now() - asked));
          if (d.ok()) {
            stream->last_id = (*d)->frame->id;
            absl::StrAppend(&out, "event: detection\ndata: ", ViewDetectionJson(**d), "\n\n");
          }
          const absl::Time now = absl::Now();
          if (out.empty() && now - stream->last_write >= kKeepAlive) out = ": keep-alive\n\n";
          if (out.empty()) return true;
          stream->last_write = now;
          return sink.write(out.data(), out.size());
        },
        [this, view, box](bool /*success*/) {
          view->Watch(box, -1).IgnoreError();
          if (metrics_ != nullptr) metrics_->EventStreamsAdd(-1);
        });
  });
}

}  // namespace cornerpose::server
