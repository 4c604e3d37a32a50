// Loading cornerpose_server's configuration file (cornerpose.v1.ServerConfig
// in protobuf text format; see proto/cornerpose/v1/server_config.proto and
// deploy/config/server.textproto).
#pragma once

#include <string>

#include "absl/status/statusor.h"
#include "server/config/server_options.h"

namespace cornerpose::server {

// Reads and validates the file at `path`. Fields left unset take
// ServerOptions' defaults; a relative source directory or oni_file is
// resolved against the file's directory (device_uri is taken as is).
// NOT_FOUND when the file does not exist; INVALID_ARGUMENT (naming the file)
// for a syntax error (with the parser's line:column) or a bad value: an empty
// or duplicate source name, a source with no kind, an empty directory or
// oni_file, fps or playback_speed <= 0, a limit <= 0 (or too large), an empty box model name
// or a non-positive box size, or detector_defaults the detector refuses.
absl::StatusOr<ServerOptions> LoadServerConfig(const std::string& path);

}  // namespace cornerpose::server
