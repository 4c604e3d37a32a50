// Boxes between protobuf and the plain box types (common/box): sizes, faces,
// detected boxes and the configuration's named box models, both ways. With
// geometry_wire.h the part of the wire library that needs no perception
// core (target cornerpose_wire_box), so the robot-cell daemon links it alone.
#pragma once

#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "common/box/box_models.h"
#include "common/box/box_types.h"
#include "cornerpose/v1/geometry.pb.h"
#include "cornerpose/v1/perception_service.pb.h"
#include "google/protobuf/map.h"

namespace cornerpose::wire {

// Not validated: BoxDims::Validate says what is wrong with which side.
BoxDims BoxDimsFromProto(const v1::BoxDimensions& box);
v1::BoxDimensions ToProto(const BoxDims& box);

v1::BoxFace ToProto(BoxFace face);
// The inverse of ToProto(BoxFace). INVALID_ARGUMENT for
// BOX_FACE_UNSPECIFIED or an unknown value.
absl::StatusOr<BoxFace> BoxFaceFromProto(v1::BoxFace face);

// The pose, score, grasp face, its centre and normal (the supporting
// segments and corner count stay on the server).
v1::DetectedBox ToProto(const DetectedBox& box);
// INVALID_ARGUMENT naming `field` for a zero quaternion or an unspecified
// grasp face.
absl::StatusOr<DetectedBox> DetectedBoxFromProto(const v1::DetectedBox& box,
                                                 absl::string_view field);
// The boxes of a response, best score first ("boxes[i]" in errors).
absl::StatusOr<std::vector<DetectedBox>> BoxesFromProto(const v1::DetectResponse& response);

// A configuration's box_models. INVALID_ARGUMENT for an empty name or a
// side that is not a positive, finite number of metres.
absl::StatusOr<BoxModels> BoxModelsFromProto(
    const google::protobuf::Map<std::string, v1::BoxDimensions>& models);

}  // namespace cornerpose::wire
