// Reading a configuration file written in protobuf text format (the
// server's and the daemon's configuration files).
#pragma once

#include <google/protobuf/message.h>

#include <string>

#include "absl/status/status.h"

namespace cornerpose {

// Parses the file at `path` into *message. NOT_FOUND when it does not exist
// or cannot be opened; INVALID_ARGUMENT "PATH: ..." when it is not a regular
// file, or for syntax errors and unknown fields, with the parser's 1-based
// "line:column: message" for each.
absl::Status ReadTextProtoFile(const std::string& path, google::protobuf::Message* message);

}  // namespace cornerpose
