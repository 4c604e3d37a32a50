// cornerpose_robot_client: the robot-cell daemon. Subscribes to a
// perception service's detections, picks boxes with a UR arm and places them
// on a pattern, and serves its state (cornerpose.v1.RobotClientService and
// gRPC health) for operators and monitoring.
//
//   cornerpose_robot_client --config deploy/config/robot_client.textproto
//       [--server HOST:PORT] [--source NAME] [--robot_host HOST] [--dry_run]
//
// Flags given override the file. Prints one line per pick and per state
// change; runs until the place pattern is full, max_picks are made, or
// SIGINT / SIGTERM: a running program is then stopped through the
// dashboard and confirmed stopped (robot.stop_confirm_timeout_s, 3 s by
// default), its pick logged UNKNOWN, and the daemon exits 0, well inside the
// systemd unit's TimeoutStopSec (20 s).
#include <semaphore.h>

#include <csignal>
#include <memory>
#include <cstdio>
#include <string>
#include <thread>
#include <utility>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/flags/usage.h"
#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"
#include "absl/time/time.h"
#include "common/grpc_security/tls.h"
#include "common/logging/log.h"
#include "common/metrics/metrics_http.h"
#include "robot_client/cell/cell_controller.h"
#include "robot_client/cell/perception_subscriber.h"
#include "robot_client/cell/status_service.h"
#include "robot_client/config/robot_config.h"
#include "robot_client/metrics/daemon_metrics.h"

ABSL_FLAG(std::string, config, "",
          "the configuration file (cornerpose.v1.RobotClientConfig, protobuf text format); "
          "required");
ABSL_FLAG(std::string, server, "", "host:port of the perception service (overrides the file)");
ABSL_FLAG(std::string, source, "", "the perception service's frame source (overrides the file)");
ABSL_FLAG(std::string, robot_host, "", "the UR controller's host (overrides the file)");
ABSL_FLAG(int, dashboard_port, 0, "the controller's dashboard port (overrides the file)");
ABSL_FLAG(int, primary_port, 0, "the controller's primary interface port (overrides the file)");
ABSL_FLAG(int, rtde_port, 0, "the controller's RTDE port (overrides the file)");
ABSL_FLAG(std::string, status_listen, "",
          "host:port of the status service (overrides the file; port 0 picks one)");
ABSL_FLAG(std::string, tls_ca, "", "PEM CA of the perception service's certificate (TLS)");
ABSL_FLAG(std::string, tls_cert, "", "PEM client certificate for the perception service");
ABSL_FLAG(std::string, tls_key, "", "private key of --tls_cert");
ABSL_FLAG(std::string, tls_server_name, "",
          "name the perception service's certificate must carry (default: its host)");
ABSL_FLAG(std::string, status_tls_cert, "", "PEM certificate of the status service (TLS)");
ABSL_FLAG(std::string, status_tls_key, "", "private key of --status_tls_cert");
ABSL_FLAG(std::string, status_tls_client_ca, "",
          "PEM CA; when set, status clients must present a certificate it signed");
ABSL_FLAG(bool, dry_run, false, "print the programs instead of sending them");
ABSL_FLAG(int, max_picks, -1, "stop after this many picks (overrides the file; 0 = no limit)");
ABSL_FLAG(std::string, metrics_listen, "127.0.0.1:9108",
          "host:port of the daemon's Prometheus /metrics (port 0 picks one; empty turns it off)");
ABSL_FLAG(std::string, log_format, "text",
          "text (one readable line per pick and state change) or json (one object per line)");

namespace {

// Posted by SIGINT / SIGTERM (sem_post is async-signal-safe).
sem_t stop_requested;

void OnStopSignal(int /*signal*/) { sem_post(&stop_requested); }

std::string Timestamp() {
  return absl::FormatTime("%H:%M:%E3S", absl::Now(), absl::LocalTimeZone());
}

namespace logging = cornerpose::logging;

bool JsonLogs() { return logging::GetLogFormat() == logging::LogFormat::kJson; }

// A line for operators: printed as is in text mode (the per-pick lines keep
// their layout), one JSON object in json mode.
void Note(const std::string& message, std::initializer_list<logging::Field> fields = {}) {
  if (JsonLogs()) {
    logging::Log(logging::LogLevel::kInfo, "cell", message, fields);
    return;
  }
  std::printf("%s %s\n", Timestamp().c_str(), message.c_str());
  std::fflush(stdout);
}

int Fail(const std::string& message) {
  logging::Log(logging::LogLevel::kError, "cell", message);
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace cornerpose::robot_client;  // NOLINT: a main file
  absl::SetProgramUsageMessage(
      "The robot-cell daemon: detections in, URScript pick-and-place programs out.");
  absl::ParseCommandLine(argc, argv);
  absl::StatusOr<logging::LogFormat> log_format =
      logging::ParseLogFormat(absl::GetFlag(FLAGS_log_format));
  if (!log_format.ok()) {
    std::fprintf(stderr, "cornerpose_robot_client: --log_format: %s\n",
                 log_format.status().ToString().c_str());
    return 2;
  }
  logging::SetLogFormat(*log_format);
  const std::string config = absl::GetFlag(FLAGS_config);
  if (config.empty()) {
    Fail("--config FILE is required");
    return 2;
  }
  absl::StatusOr<RobotClientOptions> loaded = LoadRobotClientConfig(config);
  if (!loaded.ok()) return Fail(loaded.status().ToString());
  RobotClientOptions options = *std::move(loaded);
  if (const std::string v = absl::GetFlag(FLAGS_server); !v.empty()) {
    options.perception.server_address = v;
  }
  if (const std::string v = absl::GetFlag(FLAGS_source); !v.empty()) options.perception.source = v;
  if (const std::string v = absl::GetFlag(FLAGS_robot_host); !v.empty()) options.robot.host = v;
  if (const int v = absl::GetFlag(FLAGS_dashboard_port); v > 0) options.robot.dashboard_port = v;
  if (const int v = absl::GetFlag(FLAGS_primary_port); v > 0) options.robot.primary_port = v;
  if (const int v = absl::GetFlag(FLAGS_rtde_port); v > 0) options.robot.rtde_port = v;
  if (const std::string v = absl::GetFlag(FLAGS_status_listen); !v.empty()) {
    options.status_listen_address = v;
  }
  for (auto [flag, field] : {std::pair{&FLAGS_tls_ca, &options.perception.tls_ca},
                             std::pair{&FLAGS_tls_cert, &options.perception.tls_cert},
                             std::pair{&FLAGS_tls_key, &options.perception.tls_key},
                             std::pair{&FLAGS_tls_server_name, &options.perception.tls_server_name},
                             std::pair{&FLAGS_status_tls_cert, &options.status_tls_cert},
                             std::pair{&FLAGS_status_tls_key, &options.status_tls_key},
                             std::pair{&FLAGS_status_tls_client_ca, &options.status_tls_client_ca}}) {
    if (std::string v = absl::GetFlag(*flag); !v.empty()) *field = std::move(v);
  }
  if (absl::GetFlag(FLAGS_dry_run)) options.dry_run = true;
  if (const int v = absl::GetFlag(FLAGS_max_picks); v >= 0) options.max_picks = v;
  if (absl::Status s = options.Validate(); !s.ok()) return Fail(s.ToString());

  sem_init(&stop_requested, /*pshared=*/0, /*value=*/0);
  struct sigaction action = {};
  action.sa_handler = OnStopSignal;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);

  PerceptionSubscriberOptions perception;
  perception.server = options.perception.server_address;
  perception.source = options.perception.source;
  // Explicit dimensions (the config resolved box_model): the server detects
  // with exactly the size the daemon plans for, and echoes it.
  perception.box_model = options.perception.box_model;
  perception.box = options.perception.box;
  perception.initial_backoff = absl::Seconds(options.perception.reconnect_initial_s);
  perception.max_backoff = absl::Seconds(options.perception.reconnect_max_s);
  absl::StatusOr<std::shared_ptr<grpc::ChannelCredentials>> credentials =
      cornerpose::MakeChannelCredentials({.ca = options.perception.tls_ca,
                                          .cert = options.perception.tls_cert,
                                          .key = options.perception.tls_key},
                                         nullptr);
  if (!credentials.ok()) {
    std::fprintf(stderr, "cornerpose_robot_client: perception: %s\n",
                 credentials.status().ToString().c_str());
    return 1;
  }
  perception.credentials = *std::move(credentials);
  perception.tls_server_name = options.perception.tls_server_name;
  PerceptionSubscriber subscriber(perception);

  // Set once the cell exists (its status feeds the sampler).
  std::unique_ptr<DaemonMetrics> metrics;
  CellCallbacks callbacks;
  callbacks.on_pick = [&metrics](const PickRecord& pick) {
    if (metrics != nullptr) metrics->OnPick(pick);
    if (JsonLogs()) {
      const Eigen::Vector3d box = pick.plan.box.base_T_box.translation();
      logging::Log(pick.outcome == PickOutcome::kCompleted || pick.outcome == PickOutcome::kDryRun
                       ? logging::LogLevel::kInfo
                       : logging::LogLevel::kWarning,
                   "cell", "pick",
                   {{"pick_id", pick.pick_id},
                    {"outcome", PickOutcomeName(pick.outcome)},
                    {"source", pick.source},
                    {"frame_id", pick.frame_id},
                    {"score", pick.score},
                    {"box_x", box.x()},
                    {"box_y", box.y()},
                    {"box_z", box.z()},
                    {"slot", pick.plan.slot},
                    {"plan_ms", pick.plan_ms},
                    {"program_s", pick.program_s},
                    {"detail", pick.detail}});
      return;
    }
    std::printf("%s %s\n", Timestamp().c_str(), DescribePick(pick).c_str());
    std::fflush(stdout);
  };
  callbacks.on_state = [](const CellStatusSnapshot& status) {
    Note(absl::StrCat("cell ", CellStateName(status.state), status.stop_reason.empty() ? "" : ": ",
                      status.stop_reason),
         {{"state", CellStateName(status.state)}, {"stop_reason", status.stop_reason}});
  };
  callbacks.on_note = [](const std::string& note) { Note(note); };
  const bool dry_run = options.dry_run;
  callbacks.on_program = [dry_run](const std::string& name, const std::string& text) {
    if (!dry_run) return;
    std::printf("%s program %s (dry run, not sent):\n%s", Timestamp().c_str(), name.c_str(),
                text.c_str());
    std::fflush(stdout);
  };
  const std::string status_address = options.status_listen_address;
  const cornerpose::ServerTlsFiles status_tls = {.cert = options.status_tls_cert,
                                                 .key = options.status_tls_key,
                                                 .client_ca = options.status_tls_client_ca};
  Note(absl::StrCat("cornerpose_robot_client: perception ", options.perception.server_address,
                    " source '", options.perception.source, "', robot ", options.robot.host, " (",
                    dry_run ? "dry run" : "live", "), ", status_address),
       {{"perception", options.perception.server_address},
        {"source", options.perception.source},
        {"robot", options.robot.host},
        {"dry_run", dry_run},
        {"status_listen", status_address}});
  CellController cell(std::move(options), CellControllerOptions{}, &subscriber, callbacks);

  absl::StatusOr<std::unique_ptr<StatusServer>> status = StartStatusServer(status_address, &cell, status_tls);
  if (!status.ok()) return Fail(status.status().ToString());
  Note(absl::StrCat("status service on port ", (*status)->port(), " (",
                    status_tls.enabled() ? "TLS" : "plaintext", ")"),
       {{"port", (*status)->port()}, {"tls", status_tls.enabled()}});
  if (const std::string warning = cornerpose::PlaintextWarning(
          "the status service", status_address, status_tls.enabled());
      !warning.empty()) {
    std::fprintf(stderr, "cornerpose_robot_client: %s\n", warning.c_str());
  }

  metrics = std::make_unique<DaemonMetrics>([&cell, &subscriber] {
    return DaemonMetrics::Sample{cell.Status(), subscriber.frames_received()};
  });
  std::unique_ptr<cornerpose::metrics::MetricsHttpServer> metrics_http;
  if (const std::string listen = absl::GetFlag(FLAGS_metrics_listen); !listen.empty()) {
    absl::StatusOr<std::unique_ptr<cornerpose::metrics::MetricsHttpServer>> started =
        cornerpose::metrics::MetricsHttpServer::Start(listen, &metrics->registry());
    if (!started.ok()) return Fail(started.status().ToString());
    metrics_http = *std::move(started);
    Note(absl::StrCat("metrics on port ", metrics_http->port()), {{"port", metrics_http->port()}});
  }

  // The signal thread stops the cell; a finished cell wakes it through the
  // same semaphore.
  std::thread stopper([&] {
    while (sem_wait(&stop_requested) != 0) {
    }
    cell.Stop();
    subscriber.Stop();
  });
  subscriber.Start();
  cell.Run();
  sem_post(&stop_requested);
  stopper.join();
  (*status)->Shutdown();
  if (metrics_http != nullptr) metrics_http->Shutdown();
  const CellStatusSnapshot end = cell.Status();
  Note(absl::StrCat("stopped: ", end.picks_done, " picks done, ", end.picks_failed, " failed"),
       {{"picks_done", end.picks_done}, {"picks_failed", end.picks_failed}});
  metrics.reset();  // its sampler reads the cell
  return 0;
}
