// Parsing the server's --source flag.
#pragma once

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "server/server_options.h"

namespace cornerpose::server {

// Parses "NAME=DIR[:FPS[:loop|once]]", e.g. "bin=data/frames/carton_s:10:once".
// The optional parts are taken from the right only when they parse, so a
// directory may itself contain ':'. INVALID_ARGUMENT for a missing name or
// directory or an FPS that is not > 0.
absl::StatusOr<SourceSpec> ParseSourceSpec(absl::string_view text);

}  // namespace cornerpose::server
