// A serialized DetectRequest as the service meets it: the options (box, model
// name, camera, overrides) and the cloud (points, depth image, colour) through
// their validation and conversion (server/service/detect_request.h), then, on
// small frames, a detection under a deadline and the response built and read
// back as a client would.
#include <cstddef>
#include <cstdint>

#include "absl/time/clock.h"
#include "absl/time/time.h"
#include "common/perception/cancel_token.h"
#include "common/perception/detector.h"
#include "common/wire/detection_wire.h"
#include "cornerpose/v1/perception_service.pb.h"
#include "fuzz/fuzz_input.h"
#include "google/protobuf/stubs/logging.h"
#include "server/service/detect_request.h"
#include "server/service/detect_response.h"

using cornerpose::fuzz::Require;

namespace {

// Frames larger than this are converted but not detected, so one input stays
// well inside libFuzzer's time limit under the sanitizers.
constexpr size_t kMaxDetectedPoints = 160 * 120;
// The deadline each detection runs under, and how far past it the detector
// may run before the harness calls it stuck (the service's promise is ~50 ms;
// the sanitizers slow every step several times).
constexpr absl::Duration kDeadline = absl::Seconds(2);
constexpr absl::Duration kStopSlack = absl::Milliseconds(750);

bool IsRefusal(const absl::Status& status) {
  return absl::IsInvalidArgument(status) || absl::IsNotFound(status);
}

}  // namespace

// Protobuf logs every string field with bad UTF-8 it refuses: noise here.
extern "C" int LLVMFuzzerInitialize(int*, char***) {
  google::protobuf::SetLogHandler(nullptr);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  cornerpose::v1::DetectRequest request;
  if (!request.ParseFromArray(data, static_cast<int>(size))) return 0;

  static const cornerpose::DetectorOptions defaults;
  const absl::StatusOr<cornerpose::DetectorOptions> options =
      cornerpose::server::DetectorOptionsFromRequest(request, defaults);
  if (!options.ok()) {
    Require(absl::IsInvalidArgument(options.status()), "bad options are INVALID_ARGUMENT");
  }
  const absl::StatusOr<cornerpose::PointCloud> cloud =
      cornerpose::server::CloudFromRequest(request);
  if (!cloud.ok()) {
    Require(IsRefusal(cloud.status()), "a bad input is INVALID_ARGUMENT or NOT_FOUND");
    return 0;
  }
  Require(cloud->Validate().ok(), "a converted cloud is valid");
  if (!options.ok() || cloud->size() > kMaxDetectedPoints) return 0;

  const absl::Time start = absl::Now();
  const cornerpose::CancelToken cancel(start + kDeadline);
  const absl::StatusOr<cornerpose::Detection> detection =
      cornerpose::DetectBoxes(*cloud, *options, cancel);
  Require(absl::Now() - start < kDeadline + kStopSlack, "a detection stops at its deadline");
  if (!detection.ok()) {
    Require(
        absl::IsInvalidArgument(detection.status()) || absl::IsDeadlineExceeded(detection.status()),
        "a detection fails only as INVALID_ARGUMENT or DEADLINE_EXCEEDED");
    return 0;
  }
  const cornerpose::v1::DetectResponse response = cornerpose::server::MakeDetectResponse(
      *detection, *options, nullptr,
      {.include_edge_points = request.include_edge_points(), .include_cloud = false});
  Require(cornerpose::wire::DetectionFromProto(response).ok(),
          "a client can read every response the service sends");
  return 0;
}
