// Turns a DetectRequest into what the detector takes: the cloud and the
// options. Every refusal is INVALID_ARGUMENT (or NOT_FOUND for a source)
// with a message that names the field.
#pragma once

#include "absl/status/statusor.h"
#include "common/perception/detector.h"
#include "common/perception/types.h"
#include "cornerpose/v1/perception_service.pb.h"

namespace cornerpose::server {

// The cloud from `cloud` or `depth_image`. A `source` is resolved by the
// service, which owns the sources; here it is NOT_FOUND. No input at all is
// INVALID_ARGUMENT.
absl::StatusOr<PointCloud> CloudFromRequest(const v1::DetectRequest& request);

// The server's defaults with the request's box size and overrides applied,
// validated. The box comes from `box` (every side > 0) or `box_model`.
absl::StatusOr<DetectorOptions> DetectorOptionsFromRequest(const v1::DetectRequest& request,
                                                           const DetectorOptions& defaults);

}  // namespace cornerpose::server
