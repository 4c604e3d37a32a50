#include "server/config/server_config.h"

#include <cmath>
#include <filesystem>
#include <limits>
#include <set>
#include <string>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "common/config/text_proto_file.h"
#include "common/validation/range_check.h"
#include "common/wire/box_wire.h"
#include "common/wire/detector_wire.h"
#include "cornerpose/v1/server_config.pb.h"

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
    if (absl::Status s = CheckRange("max_message_bytes", int64_t{config.max_message_bytes()}, 1,
                                    std::numeric_limits<int>::max());
        !s.ok()) {
      return Invalid(path, std::string(s.message()));
    }
    options.max_message_bytes = static_cast<int>(config.max_message_bytes());
  }
  if (config.has_max_concurrent_detections()) {
    if (absl::Status s =
            CheckRange("max_concurrent_detections", int64_t{config.max_concurrent_detections()}, 1,
                       std::numeric_limits<int>::max());
        !s.ok()) {
      return Invalid(path, std::string(s.message()));
    }
    options.max_concurrent_detections = config.max_concurrent_detections();
  }
  if (config.has_max_connection_age_s()) {
    // At most a day in seconds, so the milliseconds fit gRPC's int argument.
    if (absl::Status s =
            CheckRange("max_connection_age_s", config.max_connection_age_s(), 0, 86400);
        !s.ok()) {
      return Invalid(path, std::string(s.message()));
    }
    options.max_connection_age_s = config.max_connection_age_s();
  }

  options.http.listen_address =
      config.has_http_listen() ? config.http_listen() : std::string(kDefaultHttpListen);
  options.http.cell_status_address = config.cell_status_address();
  if (!config.view_box().empty()) options.http.view_box = config.view_box();

  const std::filesystem::path base = std::filesystem::path(path).parent_path();
  const auto set_int = [&](bool has, int value, int* out) {
    if (has) *out = value;
  };
  set_int(config.has_max_queued_detections(), config.max_queued_detections(),
          &options.max_queued_detections);
  set_int(config.has_max_streams(), config.max_streams(), &options.max_streams);
  set_int(config.has_default_deadline_ms(), config.default_deadline_ms(),
          &options.default_deadline_ms);
  set_int(config.has_max_deadline_ms(), config.max_deadline_ms(), &options.max_deadline_ms);
  set_int(config.has_shutdown_grace_ms(), config.shutdown_grace_ms(), &options.shutdown_grace_ms);
  set_int(config.has_stall_timeout_ms(), config.stall_timeout_ms(), &options.stall_timeout_ms);
  const auto resolve = [&](const std::string& file) {
    if (file.empty()) return file;
    std::filesystem::path p(file);
    if (p.is_relative()) p = (base / p).lexically_normal();
    return p.string();
  };
  options.tls_cert = resolve(config.tls_cert());
  options.tls_key = resolve(config.tls_key());
  options.tls_client_ca = resolve(config.tls_client_ca());
  options.http.cell_status_tls_ca = resolve(config.cell_status_tls_ca());
  options.http.cell_status_tls_cert = resolve(config.cell_status_tls_cert());
  options.http.cell_status_tls_key = resolve(config.cell_status_tls_key());
  options.http.cell_status_tls_server_name = config.cell_status_tls_server_name();
  if (config.has_enable_reflection()) options.enable_reflection = config.enable_reflection();
  if (config.has_carry_unchanged_frames()) {
    options.carry_unchanged_frames = config.carry_unchanged_frames();
  }
  if (absl::Status s = options.Validate(); !s.ok()) return Invalid(path, std::string(s.message()));
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
    if (source.has_fps()) {
      if (absl::Status s = CheckPositive(absl::StrCat(label, ": fps"), source.fps()); !s.ok()) {
        return Invalid(path, std::string(s.message()));
      }
    }
    if (source.has_fps()) spec.fps = source.fps();
    if (source.has_loop()) spec.loop = source.loop();
    if (source.has_playback_speed()) {
      if (absl::Status s =
              CheckPositive(absl::StrCat(label, ": playback_speed"), source.playback_speed());
          !s.ok()) {
        return Invalid(path, std::string(s.message()));
      }
      spec.playback_speed = source.playback_speed();
    }
    options.sources.push_back(std::move(spec));
  }

  absl::StatusOr<BoxModels> box_models = wire::BoxModelsFromProto(config.box_models());
  if (!box_models.ok()) return Invalid(path, std::string(box_models.status().message()));
  options.box_models = *std::move(box_models);

  wire::ApplyDetectorOverrides(config.detector_defaults(), &options.detector);
  // Validated with a stand-in box: requests bring their own.
  DetectorOptions check = options.detector;
  check.box = {0.3, 0.2, 0.15};
  if (absl::Status s = check.Validate(); !s.ok()) {
    return Invalid(path, absl::StrCat("detector_defaults: ", s.message()));
  }
  return options;
}

}  // namespace cornerpose::server
