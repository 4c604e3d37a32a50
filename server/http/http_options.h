// What the server's HTTP port (web view, JSON API, /metrics) is started with.
#pragma once

#include <string>

#include "absl/status/status.h"

namespace cornerpose::server {

// cornerpose_server's default HTTP address (flag and configuration file):
// loopback, as the view has no authentication; exposing it is a choice
// (0.0.0.0:8080 in the container).
inline constexpr char kDefaultHttpListen[] = "127.0.0.1:8080";

struct HttpOptions {
  // host:port of the HTTP port; port 0 picks a free one (tests); "" = no
  // HTTP port (the default in-process, so servers in tests do not fight
  // over one port; the binary defaults to kDefaultHttpListen).
  std::string listen_address;
  // host:port of the robot-cell daemon's status service
  // (RobotClientService) for /api/cell; "" = not configured.
  std::string cell_status_address;
  // TLS to that service, as the daemon serves it (its status_tls_*): the CA
  // of its certificate, and this server's client certificate and key for a
  // daemon that requires one; the name to check its certificate for when
  // not the address's host. All empty: plaintext.
  std::string cell_status_tls_ca;
  std::string cell_status_tls_cert;
  std::string cell_status_tls_key;
  std::string cell_status_tls_server_name;
  // The box the view detects on a source's frames when the page names none:
  // a model name (built-in or the configuration's box_models) or "L,B,H".
  std::string view_box = "carton_s";
  // The most view detections per second per source and box, (0, 30]. The
  // view detects only while someone watches (an open page or a request in
  // the last view_idle_s), on the same pool as Detect and streams.
  double view_max_rate_hz = 2.0;
  // Seconds after the last request before a view stops detecting, (0, 3600].
  double view_idle_s = 10.0;
  // Frames kept per source for image.png and cloud.bin, [1, 64].
  int frames_kept = 4;
  // HTTP worker threads, [2, 256]: each open event stream holds one.
  int num_threads = 16;

  // INVALID_ARGUMENT naming the field, its value and its range.
  absl::Status Validate() const;
};

}  // namespace cornerpose::server
