#include "tools/client/request_options.h"

#include <cstdio>

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "common/box/box_models.h"

namespace cornerpose::tools {

absl::StatusOr<ClientRequestOptions> ParseClientRequestOptions(const CommandArgs& args) {
  ClientRequestOptions out;
  out.server = args.Get("server").value_or("");
  out.box_text = args.Get("box").value_or("");
  absl::StatusOr<BoxDims> box = ParseBoxDims(out.box_text);
  if (box.ok()) {
    out.box = *box;
  } else if (out.box_text.empty() || out.box_text.find(',') != std::string::npos) {
    return box.status();
  }
  // Otherwise a name only the server knows (its box_models): it resolves it,
  // and DetectResponse.box_dims_used gives the outputs its size.
  if (auto d = args.Get("deadline_ms")) {
    if (!absl::SimpleAtoi(*d, &out.deadline_ms) || out.deadline_ms <= 0) {
      return absl::InvalidArgumentError(
          absl::StrCat("--deadline_ms '", *d, "' is not a positive integer"));
    }
  }
  out.outputs.json = args.Get("json");
  out.outputs.ply = args.Get("ply");
  out.outputs.png = args.Get("png");
  out.outputs.edges = args.Get("edges");
  return out;
}

int ReportClientResult(const char* command, const absl::Status& status) {
  if (status.ok()) return 0;
  std::fprintf(stderr, "cornerpose client %s: %s: %s\n", command,
               absl::StatusCodeToString(status.code()).c_str(),
               std::string(status.message()).c_str());
  return 1;
}

int ReportUsageError(const char* command, const absl::Status& status, const char* help) {
  std::fprintf(stderr, "cornerpose client %s: %s\n\n%s", command,
               std::string(status.message()).c_str(), help);
  return 2;
}

}  // namespace cornerpose::tools
