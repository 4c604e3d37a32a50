// Loading cornerpose_server's configuration file (cornerpose.v1.ServerConfig
// in protobuf text format; see proto/cornerpose/v1/server_config.proto and
// deploy/config/server.textproto).
#pragma once

#include <string>

#include "absl/status/statusor.h"
#include "server/server_options.h"

namespace cornerpose::server {

// Reads and validates the file at `path`. Fields left unset take
// ServerOptions' defaults; a relative source directory is resolved against
// the file's directory. NOT_FOUND when the file does not exist;
// INVALID_ARGUMENT (naming the file) for a syntax error (with the parser's
// line:column) or a bad value: an empty or duplicate source name, an empty
// directory, fps <= 0, a limit <= 0 (or too large), an empty box model name
// or a non-positive box size. box_models are validated but not yet used:
// Detect knows only the built-in models.
absl::StatusOr<ServerOptions> LoadServerConfig(const std::string& path);

}  // namespace cornerpose::server
