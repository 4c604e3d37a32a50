#include "tools/client_command.h"

#include <grpcpp/create_channel.h>
#include <grpcpp/security/credentials.h>
#include <grpcpp/support/channel_arguments.h>

#include <chrono>
#include <cstdio>
#include <map>
#include <optional>
#include <string>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "common/io/cloud_io.h"
#include "common/perception/box_models.h"
#include "common/perception/camera_model.h"
#include "common/viz/detection_json.h"
#include "common/viz/detection_ply.h"
#include "common/viz/detection_png.h"
#include "cornerpose/v1/perception_service.grpc.pb.h"
#include "tools/client/response_conversion.h"
#include "tools/command_args.h"
#include "tools/detect_command.h"

namespace cornerpose::tools {
namespace {

constexpr char kUsage[] =
    "usage: cornerpose client <command> [options]\n"
    "commands:\n"
    "  detect   run the detector of a cornerpose server on a point cloud file\n"
    "run 'cornerpose client <command> --help' for the options of a command\n";

constexpr char kHelp[] =
    "usage: cornerpose client detect --server ADDR --cloud FILE --box L,B,H|NAME [outputs]\n"
    "\n"
    "  --server ADDR        host:port of a cornerpose server (cornerpose_server)\n"
    "  --cloud FILE         .pcd, .ply, or a 16-bit depth .png in millimetres (converted\n"
    "                       to a cloud here with --intrinsics, as `cornerpose detect` does)\n"
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
    "Edge points are only requested from the server when --ply, --png or --edges\n"
    "needs them (otherwise the printed and JSON edge point count is 0).\n";

absl::Status Detect(const CommandArgs& args) {
  auto get = [&](const std::string& k) { return args.Get(k); };
  const std::string server = *get("server");
  const std::string box_text = *get("box");
  absl::StatusOr<BoxDims> box = ParseBoxDims(box_text);
  if (!box.ok()) return box.status();
  int deadline_ms = 10000;
  if (auto d = get("deadline_ms")) {
    if (!absl::SimpleAtoi(*d, &deadline_ms) || deadline_ms <= 0) {
      return absl::InvalidArgumentError(
          absl::StrCat("--deadline_ms '", *d, "' is not a positive integer"));
    }
  }

  v1::DetectRequest request;
  LoadOptions load;
  std::optional<CameraIntrinsics> intrinsics;
  if (auto k = get("intrinsics")) {
    absl::StatusOr<CameraIntrinsics> parsed = ParseIntrinsics(*k);
    if (!parsed.ok()) return parsed.status();
    intrinsics = *parsed;
    load.intrinsics = *parsed;
    v1::CameraIntrinsics* ki = request.mutable_intrinsics();
    ki->set_width(static_cast<uint32_t>(parsed->width));
    ki->set_height(static_cast<uint32_t>(parsed->height));
    ki->set_fx(parsed->fx);
    ki->set_fy(parsed->fy);
    ki->set_cx(parsed->cx);
    ki->set_cy(parsed->cy);
  }
  absl::StatusOr<PointCloud> cloud = LoadPointCloud(*get("cloud"), load);
  if (!cloud.ok()) return cloud.status();

  *request.mutable_cloud() = CloudToProto(*cloud);
  if (box_text.find(',') != std::string::npos) {
    v1::BoxDimensions* b = request.mutable_box();
    b->set_l(box->l);
    b->set_b(box->b);
    b->set_h(box->h);
  } else {
    request.set_box_model(box_text);
  }
  request.set_include_edge_points(get("ply") || get("png") || get("edges"));

  grpc::ChannelArguments channel_args;
  channel_args.SetMaxReceiveMessageSize(-1);
  channel_args.SetMaxSendMessageSize(-1);
  std::shared_ptr<grpc::Channel> channel =
      grpc::CreateCustomChannel(server, grpc::InsecureChannelCredentials(), channel_args);
  std::unique_ptr<v1::PerceptionService::Stub> stub = v1::PerceptionService::NewStub(channel);
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::milliseconds(deadline_ms));
  v1::DetectResponse response;
  const grpc::Status rpc = stub->Detect(&context, request, &response);
  if (!rpc.ok()) {
    std::string message = rpc.error_message();
    if ((rpc.error_code() == grpc::StatusCode::UNAVAILABLE ||
         rpc.error_code() == grpc::StatusCode::DEADLINE_EXCEEDED) &&
        channel->GetState(false) != GRPC_CHANNEL_READY) {
      message = absl::StrCat("cannot reach server ", server, " (deadline ", deadline_ms,
                             " ms): ", message);
    }
    // grpc::StatusCode and absl::StatusCode share their values.
    return absl::Status(static_cast<absl::StatusCode>(rpc.error_code()), message);
  }
  absl::StatusOr<Detection> det = DetectionFromProto(response);
  if (!det.ok()) {
    return absl::InternalError(
        absl::StrCat("bad response from ", server, ": ", det.status().message()));
  }

  if (!args.Has("quiet")) PrintDetection(*get("cloud"), cloud->size(), *det);
  if (auto p = get("json")) {
    if (absl::Status s = WriteDetectionJson(*p, *det, *box); !s.ok()) return s;
  }
  if (auto p = get("ply")) {
    if (absl::Status s = WriteDetectionPly(*p, *cloud, *det, *box); !s.ok()) return s;
  }
  if (auto p = get("png")) {
    CameraIntrinsics camera = intrinsics.value_or(CameraIntrinsics{});
    if (cloud->organized()) {
      if (absl::StatusOr<CameraIntrinsics> k = EstimateIntrinsics(*cloud); k.ok()) camera = *k;
    }
    if (absl::Status s = WriteDetectionPng(*p, *cloud, camera, *det, *box); !s.ok()) return s;
  }
  if (auto p = get("edges")) {
    if (absl::Status s = SavePoints(*p, det->edge_points); !s.ok()) return s;
  }
  return absl::OkStatus();
}

int RunClientDetect(const std::vector<std::string>& argv) {
  for (const std::string& a : argv) {
    if (a == "--help" || a == "-h") {
      std::fputs(kHelp, stdout);
      return 0;
    }
  }
  absl::StatusOr<CommandArgs> args = ParseCommandArgs(
      argv, {"server", "cloud", "box", "intrinsics", "json", "ply", "png", "edges", "deadline_ms"},
      {"quiet"}, {"server", "cloud", "box"});
  if (!args.ok()) {
    std::fprintf(stderr, "cornerpose client: %s\n\n%s",
                 std::string(args.status().message()).c_str(), kHelp);
    return 2;
  }
  if (absl::Status s = Detect(*args); !s.ok()) {
    std::fprintf(stderr, "cornerpose client: %s: %s\n", absl::StatusCodeToString(s.code()).c_str(),
                 std::string(s.message()).c_str());
    return 1;
  }
  return 0;
}

}  // namespace

int RunClient(const std::vector<std::string>& args) {
  if (args.empty()) {
    std::fputs(kUsage, stderr);
    return 2;
  }
  const std::string& command = args[0];
  if (command == "detect") return RunClientDetect({args.begin() + 1, args.end()});
  if (command == "--help" || command == "-h" || command == "help") {
    std::fputs(kUsage, stdout);
    return 0;
  }
  std::fprintf(stderr, "cornerpose client: unknown command '%s'\n%s", command.c_str(), kUsage);
  return 2;
}

}  // namespace cornerpose::tools
