// TLS and mutual TLS for every gRPC server and client of the project (the
// perception service, the daemon's status service, the CLI, the daemon's
// perception client, the benchmarks): PEM files in, gRPC credentials out.
// Everything empty means plaintext, kept for loopback development.
#pragma once

#include <grpcpp/security/credentials.h>
#include <grpcpp/security/server_credentials.h>
#include <grpcpp/support/channel_arguments.h>

#include <memory>
#include <string>

#include "absl/status/statusor.h"

namespace cornerpose {

// A server's PEM files. cert and key go together; client_ca (needs both)
// makes a client certificate required and verified against it.
struct ServerTlsFiles {
  std::string cert;
  std::string key;
  std::string client_ca;
  bool enabled() const { return !cert.empty(); }
};

// A client's PEM files. ca: the CA that signed the server's certificate
// (empty with TLS on: the system's roots); cert and key (together): the
// client's own certificate, for a server that requires one. server_name:
// the name to check the server's certificate for, when not the target's.
struct ClientTlsFiles {
  std::string ca;
  std::string cert;
  std::string key;
  std::string server_name;
  bool enabled() const { return !ca.empty() || !cert.empty(); }
};

// Insecure credentials when `files` is empty; INVALID_ARGUMENT for a key
// without a certificate (or the reverse) or a client CA without both;
// NOT_FOUND (naming the field and path) for a file that cannot be read.
absl::StatusOr<std::shared_ptr<grpc::ServerCredentials>> MakeServerCredentials(
    const ServerTlsFiles& files);

// The same for a channel; server_name, when set, goes into `args`.
absl::StatusOr<std::shared_ptr<grpc::ChannelCredentials>> MakeChannelCredentials(
    const ClientTlsFiles& files, grpc::ChannelArguments* args);

// Whether host:port (or [v6]:port, unix:...) only listens on this machine.
bool IsLoopbackAddress(const std::string& address);

// The warning a plaintext listener beyond loopback prints, or "" when
// there is nothing to warn about.
std::string PlaintextWarning(const std::string& what, const std::string& address, bool tls);

}  // namespace cornerpose
