// One way every Validate() reports a value out of its range: the field, the
// value and the range, e.g. "motion.linear_speed_m_s must be > 0 and <= 1,
// got 3" or "selection.min_score must be in [0, 1], got 1.5". Non-finite
// values are always out of range.
#pragma once

#include <concepts>
#include <cstdint>
#include <limits>
#include <string>
#include <type_traits>

#include "absl/status/status.h"
#include "absl/strings/string_view.h"

namespace cornerpose {

// OK when lo <= value <= hi.
absl::Status CheckRange(absl::string_view field, double value, double lo, double hi);
absl::Status CheckIntegerRange(absl::string_view field, int64_t value, int64_t lo, int64_t hi);
// Counts, ports, sizes: the bounds take the value's type.
template <typename T>
requires std::integral<T> absl::Status CheckRange(absl::string_view field, T value,
                                                  std::type_identity_t<T> lo,
                                                  std::type_identity_t<T> hi) {
  return CheckIntegerRange(field, static_cast<int64_t>(value), static_cast<int64_t>(lo),
                           static_cast<int64_t>(hi));
}

// OK when 0 < value <= hi (no upper bound by default).
absl::Status CheckPositive(absl::string_view field, double value,
                           double hi = std::numeric_limits<double>::infinity());

// OK when value >= lo.
absl::Status CheckAtLeast(absl::string_view field, double value, double lo);

// A caller's name (a source, a box model) as an error message quotes it:
// escaped (C-style: no raw control bytes or invalid UTF-8 in a status) and
// at most max_bytes of it, then how long it was. A status travels in gRPC
// metadata, which a client refuses beyond 8 KiB.
std::string QuotedName(absl::string_view name, size_t max_bytes = 64);

}  // namespace cornerpose
