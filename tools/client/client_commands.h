// The `cornerpose client` commands, each talking to a running
// cornerpose_server. argv holds the arguments after the command's name. Each
// returns the process exit code: 0 on success, 1 when the RPC or an output
// fails (the status code is printed), 2 for bad usage.
#pragma once

#include <string>
#include <vector>

namespace cornerpose::tools {

// `client detect`: one detection on a cloud file or a server-side source.
int RunClientDetect(const std::vector<std::string>& argv);
// `client stream`: detections on every new frame of a server-side source.
int RunClientStream(const std::vector<std::string>& argv);
// `client health`: exits 0 when the server reports SERVING (a probe for
// containers and scripts).
int RunClientHealth(const std::vector<std::string>& argv);
// `client sources`: the server's frame sources and their state.
int RunClientSources(const std::vector<std::string>& argv);

}  // namespace cornerpose::tools
