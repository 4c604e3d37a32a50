#include "server/http/http_options.h"

#include "common/validation/range_check.h"

namespace cornerpose::server {

absl::Status HttpOptions::Validate() const {
  if (absl::Status s = CheckPositive("view_max_rate_hz", view_max_rate_hz, 30.0); !s.ok()) {
    return s;
  }
  if (absl::Status s = CheckPositive("view_idle_s", view_idle_s, 3600.0); !s.ok()) return s;
  if (absl::Status s = CheckIntegerRange("frames_kept", frames_kept, 1, 64); !s.ok()) return s;
  return CheckIntegerRange("num_threads", num_threads, 2, 256);
}

}  // namespace cornerpose::server
