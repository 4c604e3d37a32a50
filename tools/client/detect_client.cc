// `cornerpose client detect`: sends a cloud file, or names a server-side
// source, to PerceptionService.Detect and prints / writes the result exactly
// as `cornerpose detect` does offline.
#include <chrono>
#include <cstdio>
#include <optional>
#include <string>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/str_cat.h"
#include "common/box/box_models.h"
#include "common/io/cloud_io.h"
#include "common/wire/cloud_wire.h"
#include "common/wire/detection_wire.h"
#include "cornerpose/v1/perception_service.grpc.pb.h"
#include "tools/client/client_commands.h"
#include "tools/client/detection_outputs.h"
#include "tools/client/request_options.h"
#include "tools/client/rpc_channel.h"
#include "tools/command_args.h"
#include "tools/detect_command.h"

namespace cornerpose::tools {
namespace {

constexpr char kHelp[] =
    "usage: cornerpose client detect --server ADDR (--cloud FILE | --source NAME)\n"
    "                                --box L,B,H|NAME [outputs]\n"
    "\n"
    "  --server ADDR        host:port of a cornerpose server (cornerpose_server)\n"
    "  --cloud FILE         .pcd, .ply, or a 16-bit depth .png in millimetres (converted\n"
    "                       to a cloud here with --intrinsics, as `cornerpose detect` does)\n"
    "  --source NAME        instead of --cloud: detect on the newest frame of the\n"
    "                       server's source NAME (see `cornerpose client sources`)\n"
    "  --box L,B,H|NAME     box size in metres, or brick, carton_s, carton_l,\n"
    "                       carton_sq, carton_flat (the name is sent to the server)\n"
    "  --intrinsics K       fx,fy,cx,cy or width,height,fx,fy,cx,cy: the camera of a\n"
    "                       depth image, or of an unorganized cloud (sent with the cloud)\n"
    "  --deadline_ms N      deadline of the RPC, milliseconds (10000); an unreachable\n"
    "                       server fails within it\n"
    "outputs (any number; the same files as `cornerpose detect`):\n"
    "  --json OUT           boxes, edges, corners and per-stage timings\n"
    "  --ply OUT            coloured cloud with edge points, segments, boxes, corners\n"
    "  --png OUT            depth image with the same drawn over it\n"
    "  --edges OUT          edge points as a PCD\n"
    "  --quiet              print nothing but errors\n"
    "Edge points (and, with --source, the frame's cloud) are only requested from\n"
    "the server when an output needs them.\n";

absl::Status Detect(const CommandArgs& args) {
  absl::StatusOr<ClientRequestOptions> common = ParseClientRequestOptions(args);
  if (!common.ok()) return common.status();
  const std::optional<std::string> cloud_path = args.Get("cloud");
  const std::optional<std::string> source = args.Get("source");

  v1::DetectRequest request;
  SetBoxSize(*common, &request);
  request.set_include_edge_points(common->outputs.need_edge_points());
  std::optional<CameraIntrinsics> intrinsics;
  PointCloud cloud;
  if (auto k = args.Get("intrinsics")) {
    absl::StatusOr<CameraIntrinsics> parsed = ParseIntrinsics(*k);
    if (!parsed.ok()) return parsed.status();
    intrinsics = *parsed;
  }
  if (cloud_path) {
    LoadOptions load;
    load.intrinsics = intrinsics;
    absl::StatusOr<PointCloud> loaded = LoadPointCloud(*cloud_path, load);
    if (!loaded.ok()) return loaded.status();
    cloud = *std::move(loaded);
    *request.mutable_cloud() = wire::CloudToProto(cloud);
    // The camera of an unorganized cloud; an organized one (a depth image
    // made into one here) is its own camera's grid.
    if (intrinsics && !cloud.organized())
      *request.mutable_intrinsics() = wire::ToProto(*intrinsics);
  } else {
    request.set_source(*source);
    request.set_include_cloud(common->outputs.need_cloud());
  }

  absl::StatusOr<std::shared_ptr<grpc::Channel>> made =
      MakeChannel(common->server, TlsFilesFromArgs(args));
  if (!made.ok()) return made.status();
  std::shared_ptr<grpc::Channel> channel = *std::move(made);
  std::unique_ptr<v1::PerceptionService::Stub> stub = v1::PerceptionService::NewStub(channel);
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() +
                       std::chrono::milliseconds(common->deadline_ms));
  v1::DetectResponse response;
  const grpc::Status rpc = stub->Detect(&context, request, &response);
  if (!rpc.ok()) return FromRpcStatus(rpc, *channel, common->server, common->deadline_ms);
  absl::StatusOr<Detection> det = wire::DetectionFromProto(response);
  if (!det.ok()) {
    return absl::InternalError(
        absl::StrCat("bad response from ", common->server, ": ", det.status().message()));
  }
  std::string label = cloud_path.value_or("");
  if (source) {
    label = absl::StrCat(*source, " frame ", response.frame_id());
    absl::StatusOr<PointCloud> frame_cloud = wire::CloudFromProto(response.cloud());
    if (!frame_cloud.ok()) {
      return absl::InternalError(
          absl::StrCat("bad cloud from ", common->server, ": ", frame_cloud.status().message()));
    }
    cloud = *std::move(frame_cloud);
  }
  if (!args.Has("quiet")) {
    // A source's cloud is only fetched when an output draws on it.
    const bool have_cloud = cloud_path.has_value() || response.has_cloud();
    PrintDetection(label, have_cloud ? std::optional<size_t>(cloud.size()) : std::nullopt, *det);
  }
  return WriteDetectionOutputs(common->outputs, cloud, intrinsics, *det,
                               BoxUsed(*common, response));
}

}  // namespace

int RunClientDetect(const std::vector<std::string>& argv) {
  if (PrintHelpIfAsked(argv, HelpWithTls(kHelp).c_str())) return 0;
  absl::StatusOr<CommandArgs> args =
      ParseCommandArgs(argv,
                       WithTlsOptions({"server", "cloud", "source", "box", "intrinsics", "json",
                                       "ply", "png", "edges", "deadline_ms"}),
                       {"quiet"}, {"server", "box"});
  if (args.ok() && args->Get("cloud").has_value() == args->Get("source").has_value()) {
    args = absl::InvalidArgumentError("give exactly one of --cloud FILE and --source NAME");
  }
  if (!args.ok()) return ReportUsageError("detect", args.status(), HelpWithTls(kHelp).c_str());
  return ReportClientResult("detect", Detect(*args));
}

}  // namespace cornerpose::tools
