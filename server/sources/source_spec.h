// Parsing the server's --source flag.
#pragma once

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "server/config/server_options.h"

namespace cornerpose::server {

// Parses a source given on the command line:
//   NAME=DIR[:FPS[:loop|once]]          a recorded-frame directory, e.g.
//                                       "bin=data/frames/carton_s:10:once"
//   NAME=openni2:                       the first OpenNI2 device
//   NAME=openni2:URI                    the OpenNI2 device URI (taken whole,
//                                       ':' included)
//   NAME=oni:FILE[:SPEED][:loop|once]   an .oni recording (speed 1, loop)
// The optional parts are taken from the right only when they parse, so a
// path may itself contain ':' (a directory whose name starts with "oni:" or
// "openni2:" is given as "./oni:..."). INVALID_ARGUMENT for a missing name,
// directory or file, or an FPS or SPEED that is not > 0.
absl::StatusOr<SourceSpec> ParseSourceSpec(absl::string_view text);

}  // namespace cornerpose::server
