#include "common/validation/range_check.h"

#include <cmath>

#include "absl/strings/escaping.h"
#include "absl/strings/str_cat.h"

namespace cornerpose {

absl::Status CheckRange(absl::string_view field, double value, double lo, double hi) {
  if (std::isfinite(value) && value >= lo && value <= hi) return absl::OkStatus();
  return absl::InvalidArgumentError(
      absl::StrCat(field, " must be in [", lo, ", ", hi, "], got ", value));
}

absl::Status CheckIntegerRange(absl::string_view field, int64_t value, int64_t lo, int64_t hi) {
  if (value >= lo && value <= hi) return absl::OkStatus();
  return absl::InvalidArgumentError(
      absl::StrCat(field, " must be in [", lo, ", ", hi, "], got ", value));
}

absl::Status CheckPositive(absl::string_view field, double value, double hi) {
  if (std::isfinite(value) && value > 0.0 && value <= hi) return absl::OkStatus();
  return absl::InvalidArgumentError(absl::StrCat(
      field, " must be > 0", std::isinf(hi) ? "" : absl::StrCat(" and <= ", hi), ", got ", value));
}

absl::Status CheckAtLeast(absl::string_view field, double value, double lo) {
  if (std::isfinite(value) && value >= lo) return absl::OkStatus();
  return absl::InvalidArgumentError(absl::StrCat(field, " must be >= ", lo, ", got ", value));
}

std::string QuotedName(absl::string_view name, size_t max_bytes) {
  if (name.size() <= max_bytes) return absl::StrCat("'", absl::CHexEscape(name), "'");
  return absl::StrCat("'", absl::CHexEscape(name.substr(0, max_bytes)), "...' (", name.size(),
                      " bytes)");
}

}  // namespace cornerpose
