#include "server/source_spec.h"

#include <string>

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"

namespace cornerpose::server {
namespace {

// Splits "rest:last" into rest and last when there is a ':'.
bool SplitLast(absl::string_view text, absl::string_view& rest, absl::string_view& last) {
  const size_t colon = text.rfind(':');
  if (colon == absl::string_view::npos) return false;
  rest = text.substr(0, colon);
  last = text.substr(colon + 1);
  return true;
}

}  // namespace

absl::StatusOr<SourceSpec> ParseSourceSpec(absl::string_view text) {
  const size_t equals = text.find('=');
  if (equals == absl::string_view::npos || equals == 0) {
    return absl::InvalidArgumentError(
        absl::StrCat("source '", text, "': expected NAME=DIR[:FPS[:loop|once]]"));
  }
  SourceSpec spec;
  spec.name = std::string(text.substr(0, equals));
  absl::string_view path = text.substr(equals + 1);

  absl::string_view rest;
  absl::string_view last;
  if (SplitLast(path, rest, last) && (last == "loop" || last == "once")) {
    spec.loop = last == "loop";
    path = rest;
    // After a mode, the FPS is required: "DIR:loop" would be ambiguous.
    if (!SplitLast(path, rest, last) || !absl::SimpleAtod(last, &spec.fps)) {
      return absl::InvalidArgumentError(
          absl::StrCat("source '", text, "': loop|once must follow an FPS (DIR:FPS:MODE)"));
    }
    path = rest;
  } else if (double fps = 0; SplitLast(path, rest, last) && absl::SimpleAtod(last, &fps)) {
    spec.fps = fps;
    path = rest;
  }
  if (path.empty()) {
    return absl::InvalidArgumentError(absl::StrCat("source '", text, "': no directory"));
  }
  if (!(spec.fps > 0)) {
    return absl::InvalidArgumentError(
        absl::StrCat("source '", text, "': fps ", spec.fps, " must be > 0"));
  }
  spec.directory = std::string(path);
  return spec;
}

}  // namespace cornerpose::server
