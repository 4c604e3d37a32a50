// cornerpose_server: the perception service over gRPC.
//
//   cornerpose_server --listen 0.0.0.0:50051 --max_message_bytes 67108864
//       --source bin=data/frames/carton_s:5:loop --source bricks=data/frames/brick:1:once
//       --source cam=openni2: --source rec=oni:recording.oni:1:loop
//   cornerpose_server --config deploy/config/server.textproto [--listen 127.0.0.1:50051]
//
// With --config the file (cornerpose.v1.ServerConfig in text format) is
// applied first, then the flags given explicitly on the command line; any
// --source given replaces the file's sources.
//
// Runs until SIGINT or SIGTERM, then finishes the RPCs in flight and exits.
#include <semaphore.h>

#include <cerrno>
#include <csignal>
#include <iostream>
#include <string>
#include <vector>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/flags/usage.h"
#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "absl/strings/string_view.h"
#include "absl/strings/strip.h"
#include "common/grpc_security/tls.h"
#include "common/logging/log.h"
#include "common/process/frame_memory.h"
#include "server/config/server_config.h"
#include "server/config/server_options.h"
#include "server/server.h"
#include "server/sources/source_spec.h"

ABSL_FLAG(std::string, config, "",
          "a configuration file (cornerpose.v1.ServerConfig, protobuf text format); flags "
          "given on the command line override it");
ABSL_FLAG(std::string, listen, cornerpose::server::ServerOptions{}.listen_address,
          "host:port to listen on (port 0 picks a free one)");
ABSL_FLAG(int, max_message_bytes, cornerpose::server::ServerOptions{}.max_message_bytes,
          "largest request or response, bytes");
ABSL_FLAG(int, max_concurrent_detections,
          cornerpose::server::ServerOptions{}.max_concurrent_detections,
          "detections run at once; more wait in a queue");
ABSL_FLAG(int, max_connection_age_s, cornerpose::server::ServerOptions{}.max_connection_age_s,
          "ask connections older than this many seconds to reconnect (clients then re-resolve "
          "the name and reach new replicas; calls in flight are not cut); 0 = never");
ABSL_FLAG(std::string, http_listen, cornerpose::server::kDefaultHttpListen,
          "host:port of the HTTP port: the web view, its JSON API and /metrics (port 0 picks "
          "a free one; empty turns it off)");
ABSL_FLAG(std::string, cell_status_address, "",
          "host:port of the robot-cell daemon's status service, shown by the web view");
ABSL_FLAG(std::string, cell_status_tls_ca, "",
          "PEM CA of the daemon status service's certificate: TLS to --cell_status_address");
ABSL_FLAG(std::string, cell_status_tls_cert, "",
          "PEM client certificate for a status service that requires one (with "
          "--cell_status_tls_key)");
ABSL_FLAG(std::string, cell_status_tls_key, "", "PEM private key of --cell_status_tls_cert");
ABSL_FLAG(std::string, cell_status_tls_server_name, "",
          "name to check the status service's certificate for, when not the address's host");
ABSL_FLAG(std::string, view_box, cornerpose::server::HttpOptions{}.view_box,
          "the box the web view detects when the page names none (model name or L,B,H)");
ABSL_FLAG(std::string, log_format, "text", "log lines as text or json (one object per line)");
ABSL_FLAG(int, max_queued_detections, cornerpose::server::ServerOptions{}.max_queued_detections,
          "Detect requests that may wait for a worker; one more is RESOURCE_EXHAUSTED");
ABSL_FLAG(int, max_streams, cornerpose::server::ServerOptions{}.max_streams,
          "StreamDetections calls open at once; one more is RESOURCE_EXHAUSTED");
ABSL_FLAG(int, default_deadline_ms, cornerpose::server::ServerOptions{}.default_deadline_ms,
          "deadline of a Detect that brings none, ms");
ABSL_FLAG(int, max_deadline_ms, cornerpose::server::ServerOptions{}.max_deadline_ms,
          "longest a Detect may take whatever its deadline, ms");
ABSL_FLAG(int, shutdown_grace_ms, cornerpose::server::ServerOptions{}.shutdown_grace_ms,
          "on SIGTERM, how long RPCs in flight may finish before they are cancelled, ms");
ABSL_FLAG(int, stall_timeout_ms, cornerpose::server::ServerOptions{}.stall_timeout_ms,
          "health is NOT_SERVING while detections wait and none finished for this long, ms");
ABSL_FLAG(std::string, tls_cert, "", "PEM certificate (chain) of the server; with --tls_key: TLS");
ABSL_FLAG(std::string, tls_key, "", "PEM private key of --tls_cert");
ABSL_FLAG(std::string, tls_client_ca, "",
          "PEM CA bundle; when set, clients must present a certificate it signed (mutual TLS)");
ABSL_FLAG(bool, carry_unchanged_frames, cornerpose::server::ServerOptions{}.carry_unchanged_frames,
          "streams and Detect on a source: a frame showing the same scene as the last one "
          "detected on gets its detection without a detector run");
ABSL_FLAG(bool, reflection, cornerpose::server::ServerOptions{}.enable_reflection,
          "serve gRPC reflection (off in production)");
ABSL_FLAG(std::vector<std::string>, source, {},
          "a frame source: NAME=DIR[:FPS[:loop|once]] (recorded frames, default 5 fps, loop), "
          "NAME=openni2:[URI] (an OpenNI2 camera; empty URI = any), or "
          "NAME=oni:FILE[:SPEED][:loop|once] (an OpenNI2 recording); repeat the flag or "
          "separate with commas for several");

namespace {

// Posted by the stop signals. gRPC starts threads before main (static
// initializers), so sigwait on a blocked mask would miss signals delivered
// to them; a handler runs whichever thread takes the signal, and sem_post is
// async-signal-safe.
sem_t stop_requested;
volatile std::sig_atomic_t stop_signal = 0;

void OnStopSignal(int signal) {
  stop_signal = signal;
  sem_post(&stop_requested);
}

// Every value of --source on the command line. absl keeps only the last
// occurrence of a flag, but several sources are naturally given as repeated
// flags, so they are collected here before absl parses (which still
// validates the syntax and serves --help).
std::vector<std::string> AllSourceFlags(int argc, char** argv) {
  std::vector<std::string> values;
  for (int i = 1; i < argc; ++i) {
    const absl::string_view arg = argv[i];
    if (arg == "--") break;
    absl::string_view value;
    if (arg == "--source" || arg == "-source") {
      if (i + 1 >= argc) break;
      value = argv[++i];
    } else if (absl::StartsWith(arg, "--source=")) {
      value = arg.substr(9);
    } else if (absl::StartsWith(arg, "-source=")) {
      value = arg.substr(8);
    } else {
      continue;
    }
    for (absl::string_view part : absl::StrSplit(value, ',', absl::SkipEmpty())) {
      values.emplace_back(part);
    }
  }
  return values;
}

// Whether --NAME (or -NAME, with or without =VALUE) is on the command line.
// absl does not expose this publicly, and the file's values must only be
// overridden by flags that were actually given.
bool SpecifiedOnCommandLine(int argc, char** argv, absl::string_view name) {
  for (int i = 1; i < argc; ++i) {
    absl::string_view arg = argv[i];
    if (arg == "--") break;
    if (!absl::ConsumePrefix(&arg, "--")) {
      if (!absl::ConsumePrefix(&arg, "-")) continue;
    }
    if (arg == name || (absl::StartsWith(arg, name) && arg.substr(name.size(), 1) == "=")) {
      return true;
    }
  }
  return false;
}

}  // namespace

int main(int argc, char** argv) {
  cornerpose::KeepFrameMemoryInProcess();
  absl::SetProgramUsageMessage("Serves cornerpose.v1.PerceptionService over gRPC.");
  const std::vector<std::string> source_flags = AllSourceFlags(argc, argv);
  absl::ParseCommandLine(argc, argv);
  namespace logging = cornerpose::logging;
  absl::StatusOr<logging::LogFormat> log_format =
      logging::ParseLogFormat(absl::GetFlag(FLAGS_log_format));
  if (!log_format.ok()) {
    std::cerr << "cornerpose_server: --log_format: " << log_format.status() << "\n";
    return 2;
  }
  logging::SetLogFormat(*log_format);
  const auto fail = [](const absl::Status& status) {
    logging::Log(logging::LogLevel::kError, "server", "cannot start",
                 {{"error", std::string(status.ToString())}});
    return 1;
  };

  sem_init(&stop_requested, /*pshared=*/0, /*value=*/0);
  struct sigaction action = {};
  action.sa_handler = OnStopSignal;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);

  cornerpose::server::ServerOptions options;
  const std::string config = absl::GetFlag(FLAGS_config);
  if (!config.empty()) {
    absl::StatusOr<cornerpose::server::ServerOptions> loaded =
        cornerpose::server::LoadServerConfig(config);
    if (!loaded.ok()) return fail(loaded.status());
    options = *std::move(loaded);
  }
  // Without a file every flag applies (its default matches ServerOptions').
  const auto given = [&](absl::string_view name) {
    return config.empty() || SpecifiedOnCommandLine(argc, argv, name);
  };
  if (given("listen")) options.listen_address = absl::GetFlag(FLAGS_listen);
  if (given("max_message_bytes")) {
    options.max_message_bytes = absl::GetFlag(FLAGS_max_message_bytes);
  }
  if (given("max_concurrent_detections")) {
    options.max_concurrent_detections = absl::GetFlag(FLAGS_max_concurrent_detections);
  }
  if (given("max_connection_age_s")) {
    options.max_connection_age_s = absl::GetFlag(FLAGS_max_connection_age_s);
  }
  if (given("http_listen")) options.http.listen_address = absl::GetFlag(FLAGS_http_listen);
  if (given("cell_status_address")) {
    options.http.cell_status_address = absl::GetFlag(FLAGS_cell_status_address);
  }
  if (given("cell_status_tls_ca")) {
    options.http.cell_status_tls_ca = absl::GetFlag(FLAGS_cell_status_tls_ca);
  }
  if (given("cell_status_tls_cert")) {
    options.http.cell_status_tls_cert = absl::GetFlag(FLAGS_cell_status_tls_cert);
  }
  if (given("cell_status_tls_key")) {
    options.http.cell_status_tls_key = absl::GetFlag(FLAGS_cell_status_tls_key);
  }
  if (given("cell_status_tls_server_name")) {
    options.http.cell_status_tls_server_name = absl::GetFlag(FLAGS_cell_status_tls_server_name);
  }
  if (given("view_box")) options.http.view_box = absl::GetFlag(FLAGS_view_box);
  const auto take_int = [&](absl::string_view name, const absl::Flag<int>& flag, int* out) {
    if (given(name)) *out = absl::GetFlag(flag);
  };
  take_int("max_queued_detections", FLAGS_max_queued_detections, &options.max_queued_detections);
  take_int("max_streams", FLAGS_max_streams, &options.max_streams);
  take_int("default_deadline_ms", FLAGS_default_deadline_ms, &options.default_deadline_ms);
  take_int("max_deadline_ms", FLAGS_max_deadline_ms, &options.max_deadline_ms);
  take_int("shutdown_grace_ms", FLAGS_shutdown_grace_ms, &options.shutdown_grace_ms);
  take_int("stall_timeout_ms", FLAGS_stall_timeout_ms, &options.stall_timeout_ms);
  if (given("tls_cert")) options.tls_cert = absl::GetFlag(FLAGS_tls_cert);
  if (given("tls_key")) options.tls_key = absl::GetFlag(FLAGS_tls_key);
  if (given("tls_client_ca")) options.tls_client_ca = absl::GetFlag(FLAGS_tls_client_ca);
  if (given("carry_unchanged_frames") ||
      SpecifiedOnCommandLine(argc, argv, "nocarry_unchanged_frames")) {
    options.carry_unchanged_frames = absl::GetFlag(FLAGS_carry_unchanged_frames);
  }
  if (given("reflection") || SpecifiedOnCommandLine(argc, argv, "noreflection")) {
    options.enable_reflection = absl::GetFlag(FLAGS_reflection);
  }
  if (!source_flags.empty()) options.sources.clear();
  for (const std::string& text : source_flags) {
    absl::StatusOr<cornerpose::server::SourceSpec> spec = cornerpose::server::ParseSourceSpec(text);
    if (!spec.ok()) return fail(spec.status());
    options.sources.push_back(*std::move(spec));
  }

  auto server = cornerpose::server::StartServer(options);
  if (!server.ok()) return fail(server.status());
  // "listening on A (port N)": what scripts and tests look for in either format.
  logging::Log(
      logging::LogLevel::kInfo, "server",
      absl::StrCat("listening on ", options.listen_address, " (port ", (*server)->port(), ")"),
      {{"address", options.listen_address}, {"port", (*server)->port()}});
  if ((*server)->http_port() != 0) {
    logging::Log(logging::LogLevel::kInfo, "server",
                 absl::StrCat("http listening on ", options.http.listen_address, " (port ",
                              (*server)->http_port(), ")"),
                 {{"address", options.http.listen_address}, {"port", (*server)->http_port()}});
  }
  for (const cornerpose::server::SourceSpec& spec : options.sources) {
    logging::Log(logging::LogLevel::kInfo, "server", "source",
                 {{"name", spec.name},
                  {"where", spec.kind == cornerpose::server::SourceKind::kDirectory ? spec.directory
                                                                                    : spec.uri}});
  }
  // A line of its own: scripts and tests match the one above.
  logging::Log(
      logging::LogLevel::kInfo, "server",
      absl::StrCat(options.tls_client_ca.empty() ? (options.tls_cert.empty() ? "plaintext" : "TLS")
                                                 : "mutual TLS",
                   options.enable_reflection ? ", reflection on" : ", reflection off"),
      {{"tls", options.tls_client_ca.empty() ? (options.tls_cert.empty() ? "plaintext" : "tls")
                                             : "mutual_tls"},
       {"reflection", options.enable_reflection}});
  if (const std::string warning = cornerpose::PlaintextWarning(
          "cornerpose_server", options.listen_address, !options.tls_cert.empty());
      !warning.empty()) {
    logging::Log(logging::LogLevel::kWarning, "server", warning);
  }

  while (sem_wait(&stop_requested) != 0 && errno == EINTR) {
  }
  logging::Log(logging::LogLevel::kInfo, "server", "shutting down",
               {{"signal", static_cast<int>(stop_signal)}});
  (*server)->Shutdown();
  return 0;
}
