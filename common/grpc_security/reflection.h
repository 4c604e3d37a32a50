// gRPC server reflection as a per-server switch. The reflection plugin is a
// process-wide registration (every ServerBuilder made after it gets the
// service), so a server that wants it off removes the plugin from its own
// builder.
#pragma once

#include <grpcpp/server_builder.h>

namespace cornerpose {

// Registers the reflection plugin (once per process) and, when `enabled` is
// false, drops it from `builder`.
void ConfigureReflection(grpc::ServerBuilder& builder, bool enabled);

}  // namespace cornerpose
