#include "common/wire/geometry_wire.h"

#include <cmath>

#include "absl/strings/str_cat.h"

namespace cornerpose::wire {

v1::Vector3 ToProto(const Eigen::Vector3d& v) {
  v1::Vector3 out;
  out.set_x(v.x());
  out.set_y(v.y());
  out.set_z(v.z());
  return out;
}

v1::Vector3 ToProto(const Eigen::Vector3f& v) { return ToProto(Eigen::Vector3d(v.cast<double>())); }

v1::Quaternion ToProto(const Eigen::Quaterniond& q) {
  Eigen::Quaterniond unit = q.normalized();
  if (unit.w() < 0.0) unit.coeffs() = -unit.coeffs();
  v1::Quaternion out;
  out.set_w(unit.w());
  out.set_x(unit.x());
  out.set_y(unit.y());
  out.set_z(unit.z());
  return out;
}

v1::Pose ToProto(const Eigen::Isometry3d& parent_T_child) {
  v1::Pose out;
  *out.mutable_position() = ToProto(Eigen::Vector3d(parent_T_child.translation()));
  *out.mutable_orientation() = ToProto(Eigen::Quaterniond(parent_T_child.rotation()));
  return out;
}

Eigen::Vector3d Vector3dFromProto(const v1::Vector3& v) { return {v.x(), v.y(), v.z()}; }

Eigen::Vector3f Vector3fFromProto(const v1::Vector3& v) {
  return Vector3dFromProto(v).cast<float>();
}

absl::StatusOr<Eigen::Isometry3d> PoseFromProto(const v1::Pose& pose, absl::string_view field,
                                                OrientationCheck check) {
  const v1::Quaternion& q = pose.orientation();
  const Eigen::Quaterniond quaternion(q.w(), q.x(), q.y(), q.z());
  const double norm = quaternion.norm();
  switch (check) {
    case OrientationCheck::kUnit:
      if (!std::isfinite(norm) || std::abs(norm - 1.0) > 1e-3) {
        return absl::InvalidArgumentError(
            absl::StrCat(field, ".orientation must be a unit quaternion (w x y z), got norm ", norm,
                         " for (", q.w(), ", ", q.x(), ", ", q.y(), ", ", q.z(), ")"));
      }
      break;
    case OrientationCheck::kNonZero:
      if (!(norm > 1e-9) || !std::isfinite(norm)) {
        return absl::InvalidArgumentError(absl::StrCat(field, ".orientation is not a rotation"));
      }
      break;
  }
  const Eigen::Vector3d position = Vector3dFromProto(pose.position());
  if (!position.allFinite()) {
    return absl::InvalidArgumentError(absl::StrCat(field, ".position is not finite"));
  }
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = quaternion.normalized().toRotationMatrix();
  T.translation() = position;
  return T;
}

}  // namespace cornerpose::wire
