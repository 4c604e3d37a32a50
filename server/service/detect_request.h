// Turns a DetectRequest into what the detector takes: the cloud and the
// options. Every refusal is INVALID_ARGUMENT (or NOT_FOUND for a source)
// with a message that names the field.
#pragma once

#include <map>
#include <string>

#include "absl/status/statusor.h"
#include "common/perception/detector.h"
#include "common/perception/types.h"
#include "cornerpose/v1/perception_service.pb.h"

namespace cornerpose::server {

// The cloud from `cloud` or `depth_image`. A `source` is resolved by the
// service, which owns the sources; here it is NOT_FOUND. No input at all is
// INVALID_ARGUMENT.
absl::StatusOr<PointCloud> CloudFromRequest(const v1::DetectRequest& request);

// Box sizes by model name (the server configuration's box_models).
using BoxModels = std::map<std::string, BoxDims>;

// The server's defaults with the request's box size and overrides applied,
// validated. The box comes from `box` (every side > 0) or `box_model`: a
// name in `models` first, then a built-in model.
absl::StatusOr<DetectorOptions> DetectorOptionsFromRequest(const v1::DetectRequest& request,
                                                           const DetectorOptions& defaults,
                                                           const BoxModels& models = {});

// Applies the set fields of `overrides` to *options (a request's
// overrides, or the server configuration's detector_defaults); the caller
// validates the result.
void ApplyDetectorOverrides(const v1::DetectorOverrides& overrides, DetectorOptions* options);

}  // namespace cornerpose::server
