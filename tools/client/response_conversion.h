// The client side of the wire format: a DetectResponse converted back into
// the detector's types (server/conversion.h goes the other way, and packs
// clouds for both sides).
#pragma once

#include "absl/status/statusor.h"
#include "common/perception/types.h"
#include "cornerpose/v1/geometry.pb.h"
#include "cornerpose/v1/perception_service.pb.h"

namespace cornerpose::tools {

// The inverse of server::ToProto(BoxFace). INVALID_ARGUMENT for
// BOX_FACE_UNSPECIFIED or an unknown value.
absl::StatusOr<BoxFace> BoxFaceFromProto(v1::BoxFace face);

// Boxes (pose from position + unit quaternion), segments (the line point and
// direction rebuilt from the extremities), corners (without the segment
// indices, which the wire does not carry), edge points (when the response has
// them) and timings. INVALID_ARGUMENT for a box with a zero quaternion or an
// unspecified grasp face.
absl::StatusOr<Detection> DetectionFromProto(const v1::DetectResponse& response);

}  // namespace cornerpose::tools
