#include "tools/client/rpc_channel.h"

#include <grpcpp/create_channel.h>
#include <grpcpp/security/credentials.h>
#include <grpcpp/support/channel_arguments.h>

#include "absl/strings/str_cat.h"

namespace cornerpose::tools {

std::string HelpWithTls(const char* help) { return absl::StrCat(help, kTlsHelp); }

std::vector<std::string> WithTlsOptions(std::vector<std::string> options) {
  options.insert(options.end(), kTlsOptions.begin(), kTlsOptions.end());
  return options;
}

ClientTlsFiles TlsFilesFromArgs(const CommandArgs& args) {
  return {.ca = args.Get("tls_ca").value_or(""),
          .cert = args.Get("tls_cert").value_or(""),
          .key = args.Get("tls_key").value_or(""),
          .server_name = args.Get("tls_server_name").value_or("")};
}

absl::StatusOr<std::shared_ptr<grpc::Channel>> MakeChannel(const std::string& server,
                                                           const ClientTlsFiles& tls) {
  grpc::ChannelArguments channel_args;
  channel_args.SetMaxReceiveMessageSize(-1);
  channel_args.SetMaxSendMessageSize(-1);
  // Per-call balancing over every address the name resolves to (a headless
  // Kubernetes Service lists each replica; see deploy/k8s/service.yaml).
  channel_args.SetLoadBalancingPolicyName("round_robin");
  absl::StatusOr<std::shared_ptr<grpc::ChannelCredentials>> credentials =
      MakeChannelCredentials(tls, &channel_args);
  if (!credentials.ok()) return credentials.status();
  return grpc::CreateCustomChannel(server, *credentials, channel_args);
}

absl::Status FromRpcStatus(const grpc::Status& rpc, grpc::Channel& channel,
                           const std::string& server, int deadline_ms) {
  if (rpc.ok()) return absl::OkStatus();
  std::string message = rpc.error_message();
  if ((rpc.error_code() == grpc::StatusCode::UNAVAILABLE ||
       rpc.error_code() == grpc::StatusCode::DEADLINE_EXCEEDED) &&
      channel.GetState(false) != GRPC_CHANNEL_READY) {
    message =
        absl::StrCat("cannot reach server ", server, " (deadline ", deadline_ms, " ms): ", message);
  }
  return absl::Status(static_cast<absl::StatusCode>(rpc.error_code()), message);
}

}  // namespace cornerpose::tools
