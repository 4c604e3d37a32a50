// `cornerpose client sources`: PerceptionService.ListSources, one line per
// source: name, state, description and why it is in that state.
#include <chrono>
#include <cstdio>
#include <string>

#include "absl/status/status.h"
#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "cornerpose/v1/perception_service.grpc.pb.h"
#include "tools/client/client_commands.h"
#include "tools/client/request_options.h"
#include "tools/client/rpc_channel.h"
#include "tools/command_args.h"

namespace cornerpose::tools {
namespace {

constexpr char kHelp[] =
    "usage: cornerpose client sources --server ADDR [--deadline_ms N]\n"
    "\n"
    "Lists the frame sources of a cornerpose server: name, state (STARTING,\n"
    "RUNNING, FAILED, FINISHED), what it reads, and the reason of a failure.\n";

absl::Status ListSources(const CommandArgs& args) {
  const std::string server = *args.Get("server");
  int deadline_ms = 5000;
  if (absl::Status s = args.SetInt("deadline_ms", &deadline_ms); !s.ok()) return s;
  absl::StatusOr<std::shared_ptr<grpc::Channel>> made = MakeChannel(server, TlsFilesFromArgs(args));
  if (!made.ok()) return made.status();
  std::shared_ptr<grpc::Channel> channel = *std::move(made);
  std::unique_ptr<v1::PerceptionService::Stub> stub = v1::PerceptionService::NewStub(channel);
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::milliseconds(deadline_ms));
  v1::ListSourcesResponse response;
  const grpc::Status rpc = stub->ListSources(&context, v1::ListSourcesRequest(), &response);
  if (!rpc.ok()) return FromRpcStatus(rpc, *channel, server, deadline_ms);
  if (response.sources().empty()) std::printf("no sources\n");
  for (const v1::Source& source : response.sources()) {
    std::string state = v1::SourceState_Name(source.state());
    if (absl::StartsWith(state, "SOURCE_STATE_")) state = state.substr(13);
    const std::string reason =
        source.state_reason().empty() ? "" : absl::StrCat("  (", source.state_reason(), ")");
    std::printf("%s  %s  %s%s\n", source.name().c_str(), state.c_str(),
                source.description().c_str(), reason.c_str());
  }
  return absl::OkStatus();
}

}  // namespace

int RunClientSources(const std::vector<std::string>& argv) {
  if (PrintHelpIfAsked(argv, HelpWithTls(kHelp).c_str())) return 0;
  absl::StatusOr<CommandArgs> args =
      ParseCommandArgs(argv, WithTlsOptions({"server", "deadline_ms"}), {}, {"server"});
  if (!args.ok()) return ReportUsageError("sources", args.status(), HelpWithTls(kHelp).c_str());
  return ReportClientResult("sources", ListSources(*args));
}

}  // namespace cornerpose::tools
