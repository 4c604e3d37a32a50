#include "server/service/detect_request.h"

#include "absl/strings/str_cat.h"
#include "common/perception/box_models.h"
#include "server/conversion.h"

namespace cornerpose::server {

absl::StatusOr<PointCloud> CloudFromRequest(const v1::DetectRequest& request) {
  switch (request.input_case()) {
    case v1::DetectRequest::kCloud:
      return CloudFromProto(request.cloud());
    case v1::DetectRequest::kDepthImage:
      return CloudFromDepthImage(request.depth_image(),
                                 request.has_intrinsics() ? &request.intrinsics() : nullptr);
    case v1::DetectRequest::kSource:
      // The service grabs from its own sources before calling this; a name
      // that reaches here is not one of them.
      return absl::NotFoundError(absl::StrCat("unknown source '", request.source(), "'"));
    case v1::DetectRequest::INPUT_NOT_SET:
      break;
  }
  return absl::InvalidArgumentError("request has no input: set cloud, depth_image or source");
}

absl::StatusOr<DetectorOptions> DetectorOptionsFromRequest(const v1::DetectRequest& request,
                                                           const DetectorOptions& defaults,
                                                           const BoxModels& models) {
  DetectorOptions options = defaults;
  switch (request.box_size_case()) {
    case v1::DetectRequest::kBox:
      options.box = BoxDimsFromProto(request.box());
      break;
    case v1::DetectRequest::kBoxModel: {
      if (auto it = models.find(request.box_model()); it != models.end()) {
        options.box = it->second;
        break;
      }
      absl::StatusOr<BoxDims> model = BoxModelByName(request.box_model());
      // An unknown name is the caller's mistake, not a missing resource.
      if (!model.ok()) return absl::InvalidArgumentError(model.status().message());
      options.box = *model;
      break;
    }
    case v1::DetectRequest::BOX_SIZE_NOT_SET:
      return absl::InvalidArgumentError("request has no box size: set box or box_model");
  }
  if (absl::Status s = options.box.Validate(); !s.ok()) return s;

  // An unorganized cloud is laid onto the pixel grid of the camera it came
  // from; the request's intrinsics name that camera.
  if (request.has_intrinsics() && request.input_case() == v1::DetectRequest::kCloud) {
    absl::StatusOr<CameraIntrinsics> camera = IntrinsicsFromProto(request.intrinsics());
    if (!camera.ok()) return camera.status();
    options.camera = *camera;
  }

  ApplyDetectorOverrides(request.overrides(), &options);
  if (absl::Status s = options.Validate(); !s.ok()) return s;
  return options;
}

void ApplyDetectorOverrides(const v1::DetectorOverrides& overrides, DetectorOptions* options) {
  if (overrides.has_edge_radius_m()) {
    options->edge_points.radius_m = overrides.edge_radius_m();
    // Algorithm 1 ends a segment at a gap wider than r_s (as the CLI does).
    options->segments.gap_m = overrides.edge_radius_m();
  }
  if (overrides.has_edge_threshold()) options->edge_points.threshold = overrides.edge_threshold();
  if (overrides.has_ransac_threshold_m()) {
    options->segments.ransac_threshold_m = overrides.ransac_threshold_m();
  }
}

}  // namespace cornerpose::server
