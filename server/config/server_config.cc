#include "server/config/server_config.h"

#include <cmath>
#include <filesystem>
#include <limits>
#include <set>
#include <string>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "common/config/text_proto_file.h"
#include "cornerpose/v1/server_config.pb.h"
#include "server/service/detect_request.h"

namespace cornerpose::server {
namespace {

absl::Status Invalid(const std::string& path, const std::string& message) {
  return absl::InvalidArgumentError(absl::StrCat(path, ": ", message));
}

}  // namespace

absl::StatusOr<ServerOptions> LoadServerConfig(const std::string& path) {
  v1::ServerConfig config;
  if (absl::Status s = ReadTextProtoFile(path, &config); !s.ok()) return s;

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
  if (config.has_max_connection_age_s()) {
    // At most a day in seconds, so the milliseconds fit gRPC's int argument.
    if (config.max_connection_age_s() < 0 || config.max_connection_age_s() > 86400) {
      return Invalid(path, absl::StrCat("max_connection_age_s must be in [0, 86400], got ",
                                        config.max_connection_age_s()));
    }
    options.max_connection_age_s = config.max_connection_age_s();
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
    const std::string label = absl::StrCat(where, " (", source.name(), ")");
    SourceSpec spec;
    spec.name = source.name();
    switch (source.kind_case()) {
      case v1::SourceConfig::kDirectory: {
        if (source.directory().empty()) return Invalid(path, label + ": empty directory");
        std::filesystem::path directory(source.directory());
        if (directory.is_relative()) directory = (base / directory).lexically_normal();
        spec.directory = directory.string();
        break;
      }
      case v1::SourceConfig::kDeviceUri:
        spec.kind = SourceKind::kOpenNi2Device;
        spec.uri = source.device_uri();
        break;
      case v1::SourceConfig::kOniFile: {
        if (source.oni_file().empty()) return Invalid(path, label + ": empty oni_file");
        spec.kind = SourceKind::kOniFile;
        std::filesystem::path file(source.oni_file());
        if (file.is_relative()) file = (base / file).lexically_normal();
        spec.uri = file.string();
        break;
      }
      case v1::SourceConfig::KIND_NOT_SET:
        return Invalid(path, label + ": set one of directory, device_uri or oni_file");
    }
    if (source.has_fps() && !(source.fps() > 0 && std::isfinite(source.fps()))) {
      return Invalid(
          path, absl::StrCat(where, " (", source.name(), "): fps must be > 0, got ", source.fps()));
    }
    if (source.has_fps()) spec.fps = source.fps();
    if (source.has_loop()) spec.loop = source.loop();
    if (source.has_playback_speed()) {
      if (!(source.playback_speed() > 0 && std::isfinite(source.playback_speed()))) {
        return Invalid(path, absl::StrCat(label, ": playback_speed must be > 0, got ",
                                          source.playback_speed()));
      }
      spec.playback_speed = source.playback_speed();
    }
    options.sources.push_back(std::move(spec));
  }

  for (const auto& [name, box] : config.box_models()) {
    if (name.empty()) return Invalid(path, "box_models: empty model name");
    if (!(box.l() > 0) || !(box.b() > 0) || !(box.h() > 0) || !std::isfinite(box.l()) ||
        !std::isfinite(box.b()) || !std::isfinite(box.h())) {
      return Invalid(path,
                     absl::StrCat("box_models[\"", name, "\"]: l, b and h must be > 0 metres"));
    }
    options.box_models[name] = BoxDims{box.l(), box.b(), box.h()};
  }

  ApplyDetectorOverrides(config.detector_defaults(), &options.detector);
  // Validated with a stand-in box: requests bring their own.
  DetectorOptions check = options.detector;
  check.box = {0.3, 0.2, 0.15};
  if (absl::Status s = check.Validate(); !s.ok()) {
    return Invalid(path, absl::StrCat("detector_defaults: ", s.message()));
  }
  return options;
}

}  // namespace cornerpose::server
