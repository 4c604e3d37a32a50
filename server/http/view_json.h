// The JSON bodies of the HTTP API (web/README.md): a source's line and a
// view detection. nlohmann::json stays in the .cc files.
#pragma once

#include <string>

#include "server/http/source_view.h"

namespace cornerpose::server {

// {"name": ..., "state": ..., "fps": ..., ...}
std::string SourceSummaryJson(const SourceSummary& summary);
// {"sources": [...]}
std::string SourceListJson(const std::vector<SourceSummary>& summaries);
// The /latest body: the detection, its frame's intrinsics and the URLs of
// its image and cloud.
std::string ViewDetectionJson(const ViewDetection& view);
// {"error": message}
std::string ErrorJson(const std::string& message);

}  // namespace cornerpose::server
