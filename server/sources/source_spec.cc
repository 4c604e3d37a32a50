#include "server/sources/source_spec.h"

#include <cmath>
#include <string>

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/strip.h"

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

absl::Status Invalid(absl::string_view text, absl::string_view message) {
  return absl::InvalidArgumentError(absl::StrCat("source '", text, "': ", message));
}

// DIR[:FPS[:loop|once]] into spec.
absl::Status ParseDirectory(absl::string_view text, absl::string_view path, SourceSpec& spec) {
  absl::string_view rest;
  absl::string_view last;
  if (SplitLast(path, rest, last) && (last == "loop" || last == "once")) {
    spec.loop = last == "loop";
    path = rest;
    // After a mode, the FPS is required: "DIR:loop" would be ambiguous.
    if (!SplitLast(path, rest, last) || !absl::SimpleAtod(last, &spec.fps)) {
      return Invalid(text, "loop|once must follow an FPS (DIR:FPS:MODE)");
    }
    path = rest;
  } else if (double fps = 0; SplitLast(path, rest, last) && absl::SimpleAtod(last, &fps)) {
    spec.fps = fps;
    path = rest;
  }
  if (path.empty()) return Invalid(text, "no directory");
  if (!(spec.fps > 0)) return Invalid(text, absl::StrCat("fps ", spec.fps, " must be > 0"));
  spec.directory = std::string(path);
  return absl::OkStatus();
}

// FILE[:SPEED][:loop|once] into spec.
absl::Status ParseOniFile(absl::string_view text, absl::string_view path, SourceSpec& spec) {
  absl::string_view rest;
  absl::string_view last;
  if (SplitLast(path, rest, last) && (last == "loop" || last == "once")) {
    spec.loop = last == "loop";
    path = rest;
  }
  if (double speed = 0; SplitLast(path, rest, last) && absl::SimpleAtod(last, &speed)) {
    spec.playback_speed = speed;
    path = rest;
  }
  if (path.empty()) return Invalid(text, "no .oni file");
  if (!(spec.playback_speed > 0) || !std::isfinite(spec.playback_speed)) {
    return Invalid(text, absl::StrCat("playback speed ", spec.playback_speed, " must be > 0"));
  }
  spec.uri = std::string(path);
  return absl::OkStatus();
}

}  // namespace

absl::StatusOr<SourceSpec> ParseSourceSpec(absl::string_view text) {
  const size_t equals = text.find('=');
  if (equals == absl::string_view::npos || equals == 0) {
    return Invalid(text,
                   "expected NAME=DIR[:FPS[:loop|once]], NAME=openni2:[URI] or "
                   "NAME=oni:FILE[:SPEED][:loop|once]");
  }
  SourceSpec spec;
  spec.name = std::string(text.substr(0, equals));
  absl::string_view value = text.substr(equals + 1);

  absl::Status parsed;
  if (absl::ConsumePrefix(&value, "openni2:")) {
    spec.kind = SourceKind::kOpenNi2Device;
    spec.uri = std::string(value);
  } else if (absl::ConsumePrefix(&value, "oni:")) {
    spec.kind = SourceKind::kOniFile;
    parsed = ParseOniFile(text, value, spec);
  } else {
    parsed = ParseDirectory(text, value, spec);
  }
  if (!parsed.ok()) return parsed;
  return spec;
}

}  // namespace cornerpose::server
