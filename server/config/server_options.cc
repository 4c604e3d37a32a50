#include "server/config/server_options.h"

#include <limits>

#include "absl/strings/str_cat.h"
#include "common/validation/range_check.h"

namespace cornerpose::server {

absl::Status ServerOptions::Validate() const {
  const int kIntMax = std::numeric_limits<int>::max();
  for (absl::Status s : {
           CheckRange("max_message_bytes", max_message_bytes, 1, kIntMax),
           CheckRange("max_concurrent_detections", max_concurrent_detections, 1, 1024),
           // At most a day, so the milliseconds fit gRPC's int argument.
           CheckRange("max_connection_age_s", max_connection_age_s, 0, 86400),
           CheckRange("max_queued_detections", max_queued_detections, 0, 10000),
           CheckRange("max_streams", max_streams, 0, 10000),
           CheckRange("max_deadline_ms", max_deadline_ms, 1, 3600000),
           CheckRange("default_deadline_ms", default_deadline_ms, 1, max_deadline_ms),
           CheckRange("shutdown_grace_ms", shutdown_grace_ms, 0, 600000),
           CheckRange("stall_timeout_ms", stall_timeout_ms, 10, 3600000),
       }) {
    if (!s.ok()) return s;
  }
  if (tls_cert.empty() != tls_key.empty()) {
    return absl::InvalidArgumentError(absl::StrCat(
        "tls_cert and tls_key go together; got tls_cert '", tls_cert, "', tls_key '", tls_key,
        "'"));
  }
  if (!tls_client_ca.empty() && tls_cert.empty()) {
    return absl::InvalidArgumentError(absl::StrCat(
        "tls_client_ca '", tls_client_ca, "' needs tls_cert and tls_key (mutual TLS is TLS)"));
  }
  return absl::OkStatus();
}

}  // namespace cornerpose::server
