// A detection between the detector's types and DetectResponse, both ways:
// what the server sends and what its clients (the CLI, the tests) read back.
// The daemon, which needs only the boxes, uses BoxesFromProto (box_wire.h).
#pragma once

#include "absl/status/statusor.h"
#include "common/perception/types.h"
#include "cornerpose/v1/perception_service.pb.h"

namespace cornerpose::wire {

// Boxes, segments, corners and timings; the edge points only when asked.
v1::DetectResponse DetectionToProto(const Detection& detection, bool include_edge_points);

// Boxes (pose from position + unit quaternion), segments (the line point and
// direction rebuilt from the extremities), corners (without the segment
// indices, which the wire does not carry), edge points (when the response has
// them) and timings. INVALID_ARGUMENT for a box with a zero quaternion or an
// unspecified grasp face.
absl::StatusOr<Detection> DetectionFromProto(const v1::DetectResponse& response);

}  // namespace cornerpose::wire
