// Detector parameters from protobuf: a request's DetectorOverrides, and the
// server configuration's detector_defaults (the same message).
#pragma once

#include "common/perception/detector.h"
#include "cornerpose/v1/perception_service.pb.h"

namespace cornerpose::wire {

// Applies the set fields of `overrides` to *options; the edge radius through
// SetEdgeRadius, which keeps the segment gap tied to it. The caller
// validates the result.
void ApplyDetectorOverrides(const v1::DetectorOverrides& overrides, DetectorOptions* options);

}  // namespace cornerpose::wire
