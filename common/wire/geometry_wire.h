// Geometry between protobuf (cornerpose/v1/geometry.proto) and Eigen:
// vectors, quaternions and poses, both ways. Part of the wire library, the
// one place protobuf messages and the plain types convert.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "cornerpose/v1/geometry.pb.h"

namespace cornerpose::wire {

v1::Vector3 ToProto(const Eigen::Vector3d& v);
v1::Vector3 ToProto(const Eigen::Vector3f& v);
// The rotation as a unit quaternion with w >= 0 (q and -q are the same
// rotation; one sign keeps responses comparable).
v1::Quaternion ToProto(const Eigen::Quaterniond& q);
v1::Pose ToProto(const Eigen::Isometry3d& parent_T_child);

Eigen::Vector3d Vector3dFromProto(const v1::Vector3& v);
Eigen::Vector3f Vector3fFromProto(const v1::Vector3& v);

// How strictly PoseFromProto checks the orientation.
enum class OrientationCheck {
  // Unit within 1e-3 (what people write in configuration files).
  kUnit,
  // Any non-zero quaternion (what a peer computed; normalised here).
  kNonZero,
};

// The pose, its quaternion normalised. INVALID_ARGUMENT naming `field`
// ("base_pose_camera.orientation must be a unit quaternion ...", "boxes[2]
// .camera_pose_box.orientation is not a rotation") for an orientation that
// fails `check` (an unset one is all zero) or a non-finite position.
absl::StatusOr<Eigen::Isometry3d> PoseFromProto(const v1::Pose& pose, absl::string_view field,
                                                OrientationCheck check = OrientationCheck::kUnit);

}  // namespace cornerpose::wire
