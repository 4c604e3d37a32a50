#include "tools/client/response_conversion.h"

#include <Eigen/Geometry>
#include <cstring>
#include <string>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"

namespace cornerpose::tools {
namespace {

Eigen::Vector3d ToEigen(const v1::Vector3& v) { return {v.x(), v.y(), v.z()}; }
Eigen::Vector3f ToEigenF(const v1::Vector3& v) { return ToEigen(v).cast<float>(); }

}  // namespace

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

absl::StatusOr<Detection> DetectionFromProto(const v1::DetectResponse& response) {
  Detection out;
  out.boxes.reserve(static_cast<size_t>(response.boxes_size()));
  for (int i = 0; i < response.boxes_size(); ++i) {
    const v1::DetectedBox& b = response.boxes(i);
    const v1::Quaternion& o = b.camera_pose_box().orientation();
    Eigen::Quaterniond q(o.w(), o.x(), o.y(), o.z());
    if (!(q.norm() > 1e-9)) {
      return absl::InvalidArgumentError(
          absl::StrCat("boxes[", i, "].camera_pose_box.orientation is not a rotation"));
    }
    absl::StatusOr<BoxFace> face = BoxFaceFromProto(b.grasp_face());
    if (!face.ok()) {
      return absl::InvalidArgumentError(absl::StrCat("boxes[", i, "].", face.status().message()));
    }
    DetectedBox box;
    box.camera_T_box = Eigen::Isometry3d::Identity();
    box.camera_T_box.linear() = q.normalized().toRotationMatrix();
    box.camera_T_box.translation() = ToEigen(b.camera_pose_box().position());
    box.score = b.score();
    box.grasp_face = *face;
    box.grasp_centre_camera = ToEigen(b.grasp_centre());
    box.grasp_normal_camera = ToEigen(b.grasp_normal());
    out.boxes.push_back(std::move(box));
  }
  out.segments.reserve(static_cast<size_t>(response.segments_size()));
  for (const v1::EdgeSegment& s : response.segments()) {
    EdgeSegment segment;
    segment.end1 = ToEigenF(s.end1());
    segment.end2 = ToEigenF(s.end2());
    segment.point = segment.end1;
    const Eigen::Vector3f d = segment.end2 - segment.end1;
    if (d.norm() > 0.0f) segment.direction = d.normalized();
    segment.num_points = static_cast<int>(s.num_points());
    out.segments.push_back(segment);
  }
  out.corners.reserve(static_cast<size_t>(response.corners_size()));
  for (const v1::Corner& c : response.corners()) {
    Corner corner;
    corner.position = ToEigenF(c.position());
    out.corners.push_back(corner);
  }
  out.edge_points.reserve(static_cast<size_t>(response.edge_points_size()));
  for (const v1::Vector3& p : response.edge_points()) out.edge_points.push_back(ToEigenF(p));
  const v1::StageTimings& t = response.timings();
  out.timings.preprocess_ms = t.preprocess_ms();
  out.timings.edge_points_ms = t.edge_points_ms();
  out.timings.edge_segments_ms = t.edge_segments_ms();
  out.timings.clubbing_ms = t.clubbing_ms();
  out.timings.poses_ms = t.poses_ms();
  out.timings.total_ms = t.total_ms();
  return out;
}

}  // namespace cornerpose::tools
