#include "server/server_config.h"

#include <google/protobuf/io/tokenizer.h>
#include <google/protobuf/text_format.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>
#include <string>
#include <system_error>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "cornerpose/v1/server_config.pb.h"

namespace cornerpose::server {
namespace {

// Keeps the parser's errors (it logs them otherwise) as "line:column: message",
// 1-based.
class CollectErrors : public google::protobuf::io::ErrorCollector {
 public:
  void AddError(int line, google::protobuf::io::ColumnNumber column,
                const std::string& message) override {
    if (!errors_.empty()) errors_ += "; ";
    absl::StrAppend(&errors_, line + 1, ":", column + 1, ": ", message);
  }
  const std::string& errors() const { return errors_; }

 private:
  std::string errors_;
};

absl::Status Invalid(const std::string& path, const std::string& message) {
  return absl::InvalidArgumentError(absl::StrCat(path, ": ", message));
}

}  // namespace

absl::StatusOr<ServerOptions> LoadServerConfig(const std::string& path) {
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error)) {
    if (std::filesystem::exists(path, error)) {
      return Invalid(path, "not a regular file");
    }
    return absl::NotFoundError(absl::StrCat("configuration file not found: ", path));
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) return absl::NotFoundError(absl::StrCat("cannot open configuration file: ", path));
  std::ostringstream text;
  text << in.rdbuf();

  v1::ServerConfig config;
  CollectErrors errors;
  google::protobuf::TextFormat::Parser parser;
  parser.RecordErrorsTo(&errors);
  if (!parser.ParseFromString(text.str(), &config)) {
    return Invalid(path, errors.errors().empty() ? "cannot parse" : errors.errors());
  }

  ServerOptions options;
  if (!config.listen_address().empty()) options.listen_address = config.listen_address();
  if (config.has_max_message_bytes()) {
    if (config.max_message_bytes() <= 0 ||
        config.max_message_bytes() > std::numeric_limits<int>::max()) {
      return Invalid(
          path, absl::StrCat("max_message_bytes must be in [1, ", std::numeric_limits<int>::max(),
                             "], got ", config.max_message_bytes()));
    }
    options.max_message_bytes = static_cast<int>(config.max_message_bytes());
  }
  if (config.has_max_concurrent_detections()) {
    if (config.max_concurrent_detections() <= 0) {
      return Invalid(path, absl::StrCat("max_concurrent_detections must be > 0, got ",
                                        config.max_concurrent_detections()));
    }
    options.max_concurrent_detections = config.max_concurrent_detections();
  }

  const std::filesystem::path base = std::filesystem::path(path).parent_path();
  std::set<std::string> names;
  for (int i = 0; i < config.sources_size(); ++i) {
    const v1::SourceConfig& source = config.sources(i);
    const std::string where = absl::StrCat("sources[", i, "]");
    if (source.name().empty()) return Invalid(path, where + ": empty name");
    if (!names.insert(source.name()).second) {
      return Invalid(path, absl::StrCat(where, ": duplicate source name \"", source.name(), "\""));
    }
    if (source.directory().empty()) {
      return Invalid(path, absl::StrCat(where, " (", source.name(), "): empty directory"));
    }
    if (source.has_fps() && !(source.fps() > 0 && std::isfinite(source.fps()))) {
      return Invalid(
          path, absl::StrCat(where, " (", source.name(), "): fps must be > 0, got ", source.fps()));
    }
    SourceSpec spec;
    spec.name = source.name();
    std::filesystem::path directory(source.directory());
    if (directory.is_relative()) directory = (base / directory).lexically_normal();
    spec.directory = directory.string();
    if (source.has_fps()) spec.fps = source.fps();
    if (source.has_loop()) spec.loop = source.loop();
    options.sources.push_back(std::move(spec));
  }

  for (const auto& [name, box] : config.box_models()) {
    if (name.empty()) return Invalid(path, "box_models: empty model name");
    if (!(box.l() > 0) || !(box.b() > 0) || !(box.h() > 0)) {
      return Invalid(path,
                     absl::StrCat("box_models[\"", name, "\"]: l, b and h must be > 0 metres"));
    }
  }
  return options;
}

}  // namespace cornerpose::server
