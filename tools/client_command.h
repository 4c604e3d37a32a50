// `cornerpose client detect`: sends a cloud file to a running cornerpose
// server (PerceptionService.Detect) and prints / writes the result exactly as
// `cornerpose detect` does offline.
#pragma once

#include <string>
#include <vector>

namespace cornerpose::tools {

// argv holds the arguments after "client" (the first is the client command,
// "detect"). Returns the process exit code: 0 on success, 1 when the RPC or
// an output fails (the gRPC code is printed), 2 for bad usage.
int RunClient(const std::vector<std::string>& args);

}  // namespace cornerpose::tools
