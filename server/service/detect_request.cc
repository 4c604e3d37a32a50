#include "server/service/detect_request.h"

#include <utility>

#include "absl/strings/str_cat.h"
#include "common/validation/range_check.h"
#include "common/wire/box_wire.h"
#include "common/wire/cloud_wire.h"
#include "common/wire/detector_wire.h"

namespace cornerpose::server {
namespace {

// What both request kinds say about the box: explicit dimensions, a model
// name, or neither.
struct RequestedBox {
  const v1::BoxDimensions* dims = nullptr;
  const std::string* model = nullptr;
};

absl::StatusOr<BoxDims> ResolveBox(const RequestedBox& requested, const BoxModels& models) {
  if (requested.dims != nullptr) return wire::BoxDimsFromProto(*requested.dims);
  if (requested.model == nullptr) {
    return absl::InvalidArgumentError("request has no box size: set box or box_model");
  }
  absl::StatusOr<BoxDims> model = ResolveBoxModel(*requested.model, models);
  // An unknown name is the caller's mistake, not a missing resource.
  if (!model.ok()) return absl::InvalidArgumentError(model.status().message());
  return model;
}

// The defaults, the box, the camera (`intrinsics`, when given) and the
// overrides, validated.
absl::StatusOr<DetectorOptions> OptionsFor(const RequestedBox& requested,
                                           const v1::DetectorOverrides& overrides,
                                           const v1::CameraIntrinsics* intrinsics,
                                           const DetectorOptions& defaults,
                                           const BoxModels& models) {
  DetectorOptions options = defaults;
  absl::StatusOr<BoxDims> box = ResolveBox(requested, models);
  if (!box.ok()) return box.status();
  options.box = *box;
  if (absl::Status s = options.box.Validate(); !s.ok()) return s;
  if (intrinsics != nullptr) {
    absl::StatusOr<CameraIntrinsics> camera = wire::IntrinsicsFromProto(*intrinsics);
    if (!camera.ok()) return camera.status();
    options.camera = *camera;
  }
  wire::ApplyDetectorOverrides(overrides, &options);
  if (absl::Status s = options.Validate(); !s.ok()) return s;
  return options;
}

}  // namespace

absl::StatusOr<PointCloud> CloudFromRequest(const v1::DetectRequest& request) {
  absl::StatusOr<PointCloud> cloud;
  switch (request.input_case()) {
    case v1::DetectRequest::kCloud:
      cloud = wire::CloudFromProto(request.cloud());
      // An organized cloud is its own camera's grid: intrinsics of another
      // size name another camera (they were ignored without a word).
      if (cloud.ok() && cloud->organized() && request.has_intrinsics() &&
          (request.intrinsics().width() != static_cast<uint32_t>(cloud->width) ||
           request.intrinsics().height() != static_cast<uint32_t>(cloud->height))) {
        return absl::InvalidArgumentError(
            absl::StrCat("intrinsics image size ", request.intrinsics().width(), " x ",
                         request.intrinsics().height(), " differs from the organized cloud's ",
                         cloud->width, " x ", cloud->height));
      }
      break;
    case v1::DetectRequest::kDepthImage:
      cloud = wire::CloudFromDepthImage(request.depth_image(),
                                        request.has_intrinsics() ? &request.intrinsics() : nullptr);
      break;
    case v1::DetectRequest::kSource:
      // The service grabs from its own sources before calling this; a name
      // that reaches here is not one of them.
      return absl::NotFoundError(absl::StrCat("unknown source ", QuotedName(request.source())));
    case v1::DetectRequest::INPUT_NOT_SET:
      return absl::InvalidArgumentError("request has no input: set cloud, depth_image or source");
  }
  if (!cloud.ok() || !request.has_color()) return cloud;
  if (cloud->has_color()) {
    return absl::InvalidArgumentError("give the colour once: cloud.rgb or color, not both");
  }
  absl::StatusOr<std::vector<uint32_t>> rgb =
      wire::ColorFromProto(request.color(), cloud->width, cloud->height);
  if (!rgb.ok()) return rgb.status();
  cloud->rgb = *std::move(rgb);
  return cloud;
}

absl::StatusOr<DetectorOptions> DetectorOptionsFromRequest(const v1::DetectRequest& request,
                                                           const DetectorOptions& defaults,
                                                           const BoxModels& models) {
  RequestedBox box;
  if (request.has_box()) box.dims = &request.box();
  if (request.has_box_model()) box.model = &request.box_model();
  // An unorganized cloud is laid onto the pixel grid of the camera it came
  // from; the request's intrinsics name that camera.
  const bool cloud_camera =
      request.has_intrinsics() && request.input_case() == v1::DetectRequest::kCloud;
  return OptionsFor(box, request.overrides(), cloud_camera ? &request.intrinsics() : nullptr,
                    defaults, models);
}

absl::StatusOr<DetectorOptions> DetectorOptionsFromRequest(
    const v1::StreamDetectionsRequest& request, const DetectorOptions& defaults,
    const BoxModels& models) {
  RequestedBox box;
  if (request.has_box()) box.dims = &request.box();
  if (request.has_box_model()) box.model = &request.box_model();
  return OptionsFor(box, request.overrides(), nullptr, defaults, models);
}

}  // namespace cornerpose::server
