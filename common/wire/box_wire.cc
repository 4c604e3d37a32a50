#include "common/wire/box_wire.h"

#include <cmath>
#include <utility>

#include "absl/strings/str_cat.h"
#include "common/wire/geometry_wire.h"

namespace cornerpose::wire {

BoxDims BoxDimsFromProto(const v1::BoxDimensions& box) { return {box.l(), box.b(), box.h()}; }

v1::BoxDimensions ToProto(const BoxDims& box) {
  v1::BoxDimensions out;
  out.set_l(box.l);
  out.set_b(box.b);
  out.set_h(box.h);
  return out;
}

v1::BoxFace ToProto(BoxFace face) {
  switch (face) {
    case BoxFace::kPlusX:
      return v1::BOX_FACE_PLUS_X;
    case BoxFace::kMinusX:
      return v1::BOX_FACE_MINUS_X;
    case BoxFace::kPlusY:
      return v1::BOX_FACE_PLUS_Y;
    case BoxFace::kMinusY:
      return v1::BOX_FACE_MINUS_Y;
    case BoxFace::kPlusZ:
      return v1::BOX_FACE_PLUS_Z;
    case BoxFace::kMinusZ:
      return v1::BOX_FACE_MINUS_Z;
  }
  return v1::BOX_FACE_UNSPECIFIED;
}

absl::StatusOr<BoxFace> BoxFaceFromProto(v1::BoxFace face) {
  switch (face) {
    case v1::BOX_FACE_PLUS_X:
      return BoxFace::kPlusX;
    case v1::BOX_FACE_MINUS_X:
      return BoxFace::kMinusX;
    case v1::BOX_FACE_PLUS_Y:
      return BoxFace::kPlusY;
    case v1::BOX_FACE_MINUS_Y:
      return BoxFace::kMinusY;
    case v1::BOX_FACE_PLUS_Z:
      return BoxFace::kPlusZ;
    case v1::BOX_FACE_MINUS_Z:
      return BoxFace::kMinusZ;
    default:
      break;
  }
  return absl::InvalidArgumentError(
      absl::StrCat("grasp_face ", static_cast<int>(face), " is not a box face"));
}

v1::DetectedBox ToProto(const DetectedBox& box) {
  v1::DetectedBox out;
  *out.mutable_camera_pose_box() = ToProto(box.camera_T_box);
  out.set_score(box.score);
  out.set_grasp_face(ToProto(box.grasp_face));
  *out.mutable_grasp_centre() = ToProto(box.grasp_centre_camera);
  *out.mutable_grasp_normal() = ToProto(box.grasp_normal_camera);
  return out;
}

absl::StatusOr<DetectedBox> DetectedBoxFromProto(const v1::DetectedBox& box,
                                                 absl::string_view field) {
  absl::StatusOr<Eigen::Isometry3d> pose = PoseFromProto(
      box.camera_pose_box(), absl::StrCat(field, ".camera_pose_box"), OrientationCheck::kNonZero);
  if (!pose.ok()) return pose.status();
  absl::StatusOr<BoxFace> face = BoxFaceFromProto(box.grasp_face());
  if (!face.ok()) {
    return absl::InvalidArgumentError(absl::StrCat(field, ".", face.status().message()));
  }
  DetectedBox out;
  out.camera_T_box = *pose;
  out.score = box.score();
  out.grasp_face = *face;
  out.grasp_centre_camera = Vector3dFromProto(box.grasp_centre());
  out.grasp_normal_camera = Vector3dFromProto(box.grasp_normal());
  return out;
}

absl::StatusOr<std::vector<DetectedBox>> BoxesFromProto(const v1::DetectResponse& response) {
  std::vector<DetectedBox> boxes;
  boxes.reserve(static_cast<size_t>(response.boxes_size()));
  for (int i = 0; i < response.boxes_size(); ++i) {
    absl::StatusOr<DetectedBox> box =
        DetectedBoxFromProto(response.boxes(i), absl::StrCat("boxes[", i, "]"));
    if (!box.ok()) return box.status();
    boxes.push_back(*std::move(box));
  }
  return boxes;
}

absl::StatusOr<BoxModels> BoxModelsFromProto(
    const google::protobuf::Map<std::string, v1::BoxDimensions>& models) {
  BoxModels out;
  for (const auto& [name, box] : models) {
    if (name.empty()) return absl::InvalidArgumentError("box_models: empty model name");
    if (!(box.l() > 0) || !(box.b() > 0) || !(box.h() > 0) || !std::isfinite(box.l()) ||
        !std::isfinite(box.b()) || !std::isfinite(box.h())) {
      return absl::InvalidArgumentError(
          absl::StrCat("box_models[\"", name, "\"]: l, b and h must be > 0 metres"));
    }
    out[name] = BoxDimsFromProto(box);
  }
  return out;
}

}  // namespace cornerpose::wire
