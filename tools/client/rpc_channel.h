// What every `cornerpose client` command shares: a channel to a server with
// no message size limits (plaintext, or TLS / mutual TLS from --tls_* ), and
// an RPC failure turned into a Status that says when the server could not be
// reached at all.
#pragma once

#include <grpcpp/channel.h>
#include <grpcpp/support/status.h>

#include <memory>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "common/grpc_security/tls.h"
#include "tools/command_args.h"

namespace cornerpose::tools {

// The TLS options every client command accepts, and their help lines.
inline const std::vector<std::string> kTlsOptions = {"tls_ca", "tls_cert", "tls_key",
                                                     "tls_server_name"};
inline constexpr char kTlsHelp[] =
    "TLS (all unset: plaintext):\n"
    "  --tls_ca FILE        PEM CA that signed the server's certificate\n"
    "  --tls_cert FILE      PEM client certificate, for a server that requires one\n"
    "  --tls_key FILE       its private key\n"
    "  --tls_server_name N  name to check the server's certificate for (default: ADDR's host)\n";

// A command's help followed by kTlsHelp.
std::string HelpWithTls(const char* help);
// `options` plus kTlsOptions.
std::vector<std::string> WithTlsOptions(std::vector<std::string> options);

// The --tls_* options of a command line.
ClientTlsFiles TlsFilesFromArgs(const CommandArgs& args);

// A channel to host:port (or any gRPC target, e.g. dns:///name:port),
// sending and receiving messages of any size (full frames exceed gRPC's
// 4 MiB default), balancing calls round robin over the addresses the name
// resolves to. Plaintext when `tls` is empty. INVALID_ARGUMENT / NOT_FOUND
// for TLS files that do not go together or cannot be read.
absl::StatusOr<std::shared_ptr<grpc::Channel>> MakeChannel(const std::string& server,
                                                           const ClientTlsFiles& tls = {});

// The RPC's status as an absl::Status (the codes share their values); when
// the channel never connected, the message names the server and deadline.
absl::Status FromRpcStatus(const grpc::Status& rpc, grpc::Channel& channel,
                           const std::string& server, int deadline_ms);

}  // namespace cornerpose::tools
