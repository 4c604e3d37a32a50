// `cornerpose client`: the commands that talk to a running cornerpose server
// (see tools/client/client_commands.h).
#pragma once

#include <string>
#include <vector>

namespace cornerpose::tools {

// argv holds the arguments after "client" (the first is the client command:
// detect, stream, sources or health). Returns the process exit code: 0 on success, 1 when the RPC
// or an output fails (the gRPC code is printed), 2 for bad usage.
int RunClient(const std::vector<std::string>& args);

}  // namespace cornerpose::tools
