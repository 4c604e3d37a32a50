// `cornerpose client health`: gRPC's standard Health/Check against a server
// (the perception service or the robot-client daemon). Exit code 0 only for
// SERVING, so containers and scripts can use it as a probe.
#include <chrono>
#include <cstdio>
#include <string>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "grpc/health/v1/health.grpc.pb.h"
#include "tools/client/client_commands.h"
#include "tools/client/request_options.h"
#include "tools/client/rpc_channel.h"
#include "tools/command_args.h"

namespace cornerpose::tools {
namespace {

constexpr char kHelp[] =
    "usage: cornerpose client health --server ADDR [--service NAME] [--deadline_ms N]\n"
    "\n"
    "Asks the server's gRPC health service; prints the status and exits 0 only\n"
    "when it is SERVING (1 otherwise, or when the server cannot be reached).\n"
    "\n"
    "  --server ADDR        host:port of a cornerpose_server or cornerpose_robot_client\n"
    "  --service NAME       the service to ask about (default \"\": the whole server)\n"
    "  --deadline_ms N      deadline of the check, milliseconds (2000)\n"
    "  --quiet              print nothing but errors\n";

absl::Status Check(const CommandArgs& args) {
  const std::string server = *args.Get("server");
  int deadline_ms = 2000;
  if (absl::Status s = args.SetInt("deadline_ms", &deadline_ms); !s.ok()) return s;
  absl::StatusOr<std::shared_ptr<grpc::Channel>> made = MakeChannel(server, TlsFilesFromArgs(args));
  if (!made.ok()) return made.status();
  std::shared_ptr<grpc::Channel> channel = *std::move(made);
  auto stub = grpc::health::v1::Health::NewStub(channel);
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::milliseconds(deadline_ms));
  grpc::health::v1::HealthCheckRequest request;
  request.set_service(args.Get("service").value_or(""));
  grpc::health::v1::HealthCheckResponse response;
  const grpc::Status rpc = stub->Check(&context, request, &response);
  if (!rpc.ok()) return FromRpcStatus(rpc, *channel, server, deadline_ms);
  const std::string status =
      grpc::health::v1::HealthCheckResponse::ServingStatus_Name(response.status());
  if (!args.Has("quiet")) std::printf("%s: %s\n", server.c_str(), status.c_str());
  if (response.status() != grpc::health::v1::HealthCheckResponse::SERVING) {
    return absl::UnavailableError(absl::StrCat(server, " is ", status));
  }
  return absl::OkStatus();
}

}  // namespace

int RunClientHealth(const std::vector<std::string>& argv) {
  if (PrintHelpIfAsked(argv, HelpWithTls(kHelp).c_str())) return 0;
  absl::StatusOr<CommandArgs> args =
      ParseCommandArgs(argv, WithTlsOptions({"server", "service", "deadline_ms"}), {"quiet"}, {"server"});
  if (!args.ok()) return ReportUsageError("health", args.status(), HelpWithTls(kHelp).c_str());
  return ReportClientResult("health", Check(*args));
}

}  // namespace cornerpose::tools
