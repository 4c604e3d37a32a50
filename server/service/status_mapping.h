// The one place an absl::Status becomes a grpc::Status.
#pragma once

#include <grpcpp/support/status.h>

#include "absl/status/status.h"

namespace cornerpose::server {

// Same code (absl's codes are google.rpc.Code, as gRPC's are), same message.
grpc::Status ToGrpcStatus(const absl::Status& status);

}  // namespace cornerpose::server
