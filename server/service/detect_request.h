// Turns a DetectRequest (or a StreamDetectionsRequest) into what the
// detector takes: the cloud and the options. The messages themselves convert
// in the wire library (common/wire); here is what the service decides: which
// input, which box (the server alone resolves model names), which camera.
// Every refusal is INVALID_ARGUMENT (or NOT_FOUND for a source) with a
// message that names the field.
#pragma once

#include "absl/status/statusor.h"
#include "common/box/box_models.h"
#include "common/perception/detector.h"
#include "common/perception/types.h"
#include "cornerpose/v1/perception_service.pb.h"

namespace cornerpose::server {

// The cloud from `cloud` or `depth_image`, with the colour of `color` (or of
// cloud.rgb) when given. A `source` is resolved by the service, which owns
// the sources; here it is NOT_FOUND. No input at all is INVALID_ARGUMENT.
absl::StatusOr<PointCloud> CloudFromRequest(const v1::DetectRequest& request);

// The server's defaults with the request's box size and overrides applied,
// validated. The box comes from `box` (every side > 0) or `box_model`: a
// name in `models` first, then a built-in model.
absl::StatusOr<DetectorOptions> DetectorOptionsFromRequest(const v1::DetectRequest& request,
                                                           const DetectorOptions& defaults,
                                                           const BoxModels& models = {});
// The same for a stream: its box and overrides validate exactly as Detect's.
absl::StatusOr<DetectorOptions> DetectorOptionsFromRequest(
    const v1::StreamDetectionsRequest& request, const DetectorOptions& defaults,
    const BoxModels& models = {});

}  // namespace cornerpose::server
