// Poses and joint vectors as the UR controller speaks them: a position in
// metres and a rotation vector (axis * angle) in the controller's base frame,
// and the URScript literals that carry them.
#pragma once

#include <Eigen/Geometry>
#include <array>
#include <string>

namespace cornerpose::ur {

// Joint angles in radians, base (shoulder pan) first, wrist 3 last.
using Joints = std::array<double, 6>;

struct UrPose {
  // Metres, controller base frame.
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  // Rotation vector (unit axis * angle), |rotation| <= pi, radians.
  Eigen::Vector3d rotation = Eigen::Vector3d::Zero();
};

// The rotation vector of `q` (normalised first), with |r| <= pi. Exact near a
// zero angle (no division by a vanishing sine) and finite at pi, where r and
// -r are the same rotation and either may be returned.
Eigen::Vector3d RotationVectorFromQuaternion(const Eigen::Quaterniond& q);
Eigen::Quaterniond QuaternionFromRotationVector(const Eigen::Vector3d& r);

UrPose ToUrPose(const Eigen::Isometry3d& T);
Eigen::Isometry3d FromUrPose(const UrPose& p);

// "p[x, y, z, rx, ry, rz]" with 6 decimals (1 um / 1 urad).
std::string FormatPoseLiteral(const UrPose& p);
// "[q1, q2, q3, q4, q5, q6]" with 6 decimals.
std::string FormatJointsLiteral(const Joints& q);

// The angle of the rotation that takes `a` to `b`, in [0, pi] radians.
double RotationAngleBetween(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b);

}  // namespace cornerpose::ur
