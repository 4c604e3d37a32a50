// What every `cornerpose client` command shares: a channel to a server with
// no message size limits, and an RPC failure turned into a Status that says
// when the server could not be reached at all.
#pragma once

#include <grpcpp/channel.h>
#include <grpcpp/support/status.h>

#include <memory>
#include <string>

#include "absl/status/status.h"

namespace cornerpose::tools {

// An insecure channel to host:port (or any gRPC target, e.g.
// dns:///name:port), sending and receiving messages of any size (full frames
// exceed gRPC's 4 MiB default), balancing calls round robin over the
// addresses the name resolves to.
std::shared_ptr<grpc::Channel> MakeChannel(const std::string& server);

// The RPC's status as an absl::Status (the codes share their values); when
// the channel never connected, the message names the server and deadline.
absl::Status FromRpcStatus(const grpc::Status& rpc, grpc::Channel& channel,
                           const std::string& server, int deadline_ms);

}  // namespace cornerpose::tools
