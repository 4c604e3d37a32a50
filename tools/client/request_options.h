// Options every `cornerpose client` detection command takes: the server,
// the box size, the deadline and the output files; and how a command reports
// its result.
#pragma once

#include <string>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "common/perception/types.h"
#include "common/wire/box_wire.h"
#include "tools/client/detection_outputs.h"
#include "tools/command_args.h"

namespace cornerpose::tools {

struct ClientRequestOptions {
  std::string server;       // --server host:port
  std::string box_text;     // --box as given: "L,B,H" or a model name
  BoxDims box;              // its dimensions, m (none for a model only the server knows)
  int deadline_ms = 10000;  // --deadline_ms, per RPC (for a stream: to its first frame)
  OutputPaths outputs;      // --json, --ply, --png, --edges
};

// Reads --server, --box, --deadline_ms and the outputs. INVALID_ARGUMENT
// names the option that does not parse.
absl::StatusOr<ClientRequestOptions> ParseClientRequestOptions(const CommandArgs& args);

// Sets the request's box: explicit dimensions for "L,B,H", else the model name
// (the server resolves the models; the response says what it used).
template <typename Request>
void SetBoxSize(const ClientRequestOptions& options, Request* request) {
  if (options.box_text.find(',') != std::string::npos) {
    *request->mutable_box() = wire::ToProto(options.box);
  } else {
    request->set_box_model(options.box_text);
  }
}

// The box a response was detected with: the size the server says it used
// (DetectResponse.box_dims_used), else the one asked for.
template <typename Response>
BoxDims BoxUsed(const ClientRequestOptions& options, const Response& response) {
  return response.has_box_dims_used() ? wire::BoxDimsFromProto(response.box_dims_used())
                                      : options.box;
}

// Prints "cornerpose client COMMAND: CODE: message" for a failure; returns
// 0 for OK, else 1.
int ReportClientResult(const char* command, const absl::Status& status);
// Prints the usage error and the command's help to stderr; returns 2.
int ReportUsageError(const char* command, const absl::Status& status, const char* help);

}  // namespace cornerpose::tools
