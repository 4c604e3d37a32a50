// `cornerpose client stream`: subscribes to PerceptionService.StreamDetections
// for one of the server's sources and prints each frame's detection as it
// arrives; optionally writes each frame's JSON / PLY / PNG into directories.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <string>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/str_cat.h"
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
    "usage: cornerpose client stream --server ADDR --source NAME --box L,B,H|NAME\n"
    "                                [--frames N] [outputs]\n"
    "\n"
    "Prints the detection on every new frame of the server's source NAME until\n"
    "--frames have arrived, the source ends, or the command is interrupted.\n"
    "A slow client gets the newest frame, never a backlog (frame ids then skip).\n"
    "A frame showing the same scene as the last one detected on carries that\n"
    "detection (\"carried from frame N\"; the server's carry_unchanged_frames).\n"
    "Ends with a count of frames received, carried and skipped.\n"
    "\n"
    "  --server ADDR        host:port of a cornerpose server (cornerpose_server)\n"
    "  --source NAME        one of the server's sources (`cornerpose client sources`)\n"
    "  --box L,B,H|NAME     box size in metres, or brick, carton_s, carton_l,\n"
    "                       carton_sq, carton_flat\n"
    "  --frames N           stop after N frames (default: run until interrupted)\n"
    "  --deadline_ms N      the first frame must arrive within N ms (10000)\n"
    "  --every_frame        every frame in order while at most a few frames behind\n"
    "                       (catching up after a slow detection) instead of the newest\n"
    "outputs, each a DIRECTORY receiving one file per frame, <source>_<frame id>.<ext>:\n"
    "  --json DIR           boxes, edges, corners and per-stage timings\n"
    "  --ply DIR            coloured cloud with edge points, segments, boxes, corners\n"
    "  --png DIR            depth image with the same drawn over it\n"
    "  --edges DIR          edge points as PCDs\n"
    "  --quiet              print nothing but errors\n";

// One output file per frame: DIR/<source>_<id>.<ext>.
std::optional<std::string> FramePath(const std::optional<std::string>& dir,
                                     const v1::DetectResponse& response, const char* ext) {
  if (!dir) return std::nullopt;
  return (std::filesystem::path(*dir) /
          absl::StrCat(response.source(), "_", response.frame_id(), ".", ext))
      .string();
}

absl::Status Stream(const CommandArgs& args) {
  absl::StatusOr<ClientRequestOptions> common = ParseClientRequestOptions(args);
  if (!common.ok()) return common.status();
  int max_frames = 0;
  if (absl::Status s = args.SetInt("frames", &max_frames); !s.ok()) return s;
  if (max_frames < 0) return absl::InvalidArgumentError("--frames must be >= 0");
  for (const std::optional<std::string>* dir : {&common->outputs.json, &common->outputs.ply,
                                                &common->outputs.png, &common->outputs.edges}) {
    if (!*dir) continue;
    std::error_code ec;
    std::filesystem::create_directories(**dir, ec);
    if (ec) {
      return absl::InvalidArgumentError(
          absl::StrCat("cannot create output directory ", **dir, ": ", ec.message()));
    }
  }

  v1::StreamDetectionsRequest request;
  request.set_source(*args.Get("source"));
  SetBoxSize(*common, &request);
  request.set_include_edge_points(common->outputs.need_edge_points());
  request.set_include_cloud(common->outputs.need_cloud());
  request.set_every_frame(args.Has("every_frame"));

  absl::StatusOr<std::shared_ptr<grpc::Channel>> made =
      MakeChannel(common->server, TlsFilesFromArgs(args));
  if (!made.ok()) return made.status();
  std::shared_ptr<grpc::Channel> channel = *std::move(made);
  // Fail fast when the server is not there; the stream itself has no deadline.
  if (!channel->WaitForConnected(std::chrono::system_clock::now() +
                                 std::chrono::milliseconds(common->deadline_ms))) {
    return absl::UnavailableError(absl::StrCat("cannot reach server ", common->server,
                                               " (deadline ", common->deadline_ms, " ms)"));
  }
  std::unique_ptr<v1::PerceptionService::Stub> stub = v1::PerceptionService::NewStub(channel);
  grpc::ClientContext context;
  std::unique_ptr<grpc::ClientReader<v1::DetectResponse>> reader =
      stub->StreamDetections(&context, request);
  v1::DetectResponse response;
  int frames = 0, carried = 0;
  uint64_t first_id = 0, last_id = 0;
  const auto summary = [&] {
    if (args.Has("quiet") || frames == 0) return;
    std::printf(
        "%d frames received (ids %llu-%llu, %llu skipped), %d carried from an earlier one\n",
        frames, static_cast<unsigned long long>(first_id), static_cast<unsigned long long>(last_id),
        static_cast<unsigned long long>(last_id - first_id + 1 - frames), carried);
  };
  while (reader->Read(&response)) {
    ++frames;
    if (first_id == 0) first_id = response.frame_id();
    last_id = response.frame_id();
    const bool was_carried =
        response.detected_frame_id() != 0 && response.detected_frame_id() != response.frame_id();
    carried += was_carried;
    absl::StatusOr<Detection> det = wire::DetectionFromProto(response);
    if (!det.ok()) {
      context.TryCancel();
      return absl::InternalError(
          absl::StrCat("bad response from ", common->server, ": ", det.status().message()));
    }
    absl::StatusOr<PointCloud> cloud = wire::CloudFromProto(response.cloud());
    if (!cloud.ok()) {
      context.TryCancel();
      return absl::InternalError(
          absl::StrCat("bad cloud from ", common->server, ": ", cloud.status().message()));
    }
    if (!args.Has("quiet")) {
      PrintDetection(
          absl::StrCat(
              response.source(), " frame ", response.frame_id(),
              was_carried ? absl::StrCat(" (carried from frame ", response.detected_frame_id(), ")")
                          : std::string()),
          response.has_cloud() ? std::optional<size_t>(cloud->size()) : std::nullopt, *det);
      std::fflush(stdout);
    }
    OutputPaths paths;
    paths.json = FramePath(common->outputs.json, response, "json");
    paths.ply = FramePath(common->outputs.ply, response, "ply");
    paths.png = FramePath(common->outputs.png, response, "png");
    paths.edges = FramePath(common->outputs.edges, response, "pcd");
    if (absl::Status s =
            WriteDetectionOutputs(paths, *cloud, std::nullopt, *det, BoxUsed(*common, response));
        !s.ok()) {
      context.TryCancel();
      return s;
    }
    if (max_frames > 0 && frames >= max_frames) {
      context.TryCancel();
      break;
    }
  }
  summary();
  const grpc::Status end = reader->Finish();
  // Cancelled by us after --frames; a source that played once ends with OK.
  if (max_frames > 0 && frames >= max_frames) return absl::OkStatus();
  return FromRpcStatus(end, *channel, common->server, common->deadline_ms);
}

}  // namespace

int RunClientStream(const std::vector<std::string>& argv) {
  if (PrintHelpIfAsked(argv, HelpWithTls(kHelp).c_str())) return 0;
  absl::StatusOr<CommandArgs> args =
      ParseCommandArgs(argv,
                       WithTlsOptions({"server", "source", "box", "frames", "json", "ply", "png",
                                       "edges", "deadline_ms"}),
                       {"quiet", "every_frame"}, {"server", "source", "box"});
  if (!args.ok()) return ReportUsageError("stream", args.status(), HelpWithTls(kHelp).c_str());
  return ReportClientResult("stream", Stream(*args));
}

}  // namespace cornerpose::tools
