#include "robot_client/ur/pose.h"

#include <cmath>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"

namespace cornerpose::ur {
namespace {

// Six decimals, without a "-0.000000" for values that round to zero.
std::string FormatNumber(double v) {
  if (std::abs(v) < 5e-7) v = 0.0;
  return absl::StrFormat("%.6f", v);
}

}  // namespace

Eigen::Vector3d RotationVectorFromQuaternion(const Eigen::Quaterniond& q_in) {
  Eigen::Quaterniond q = q_in;
  const double norm = q.norm();
  if (!(norm > 0.0) || !std::isfinite(norm)) return Eigen::Vector3d::Zero();
  q.coeffs() /= norm;
  // q and -q are the same rotation; w >= 0 keeps the angle in [0, pi].
  if (q.w() < 0.0) q.coeffs() = -q.coeffs();
  const double s = q.vec().norm();  // sin(angle / 2)
  const double angle = 2.0 * std::atan2(s, q.w());
  // angle / s -> 2 / w as s -> 0 (w -> 1): the first-order form is exact to
  // rounding there and avoids 0 / 0.
  const double scale = s > 1e-12 ? angle / s : 2.0 / q.w();
  return q.vec() * scale;
}

Eigen::Quaterniond QuaternionFromRotationVector(const Eigen::Vector3d& r) {
  const double angle = r.norm();
  if (angle < 1e-12) {
    Eigen::Quaterniond q(1.0, 0.5 * r.x(), 0.5 * r.y(), 0.5 * r.z());
    return q.normalized();
  }
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle, r / angle));
}

UrPose ToUrPose(const Eigen::Isometry3d& T) {
  UrPose p;
  p.position = T.translation();
  p.rotation = RotationVectorFromQuaternion(Eigen::Quaterniond(T.linear()));
  return p;
}

Eigen::Isometry3d FromUrPose(const UrPose& p) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = QuaternionFromRotationVector(p.rotation).toRotationMatrix();
  T.translation() = p.position;
  return T;
}

std::string FormatPoseLiteral(const UrPose& p) {
  return absl::StrCat("p[", FormatNumber(p.position.x()), ", ", FormatNumber(p.position.y()), ", ",
                      FormatNumber(p.position.z()), ", ", FormatNumber(p.rotation.x()), ", ",
                      FormatNumber(p.rotation.y()), ", ", FormatNumber(p.rotation.z()), "]");
}

std::string FormatJointsLiteral(const Joints& q) {
  return absl::StrCat(
      "[", absl::StrJoin(q, ", ", [](std::string* out, double v) { out->append(FormatNumber(v)); }),
      "]");
}

double RotationAngleBetween(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) {
  const Eigen::Quaterniond d = a.normalized().conjugate() * b.normalized();
  return 2.0 * std::atan2(d.vec().norm(), std::abs(d.w()));
}

}  // namespace cornerpose::ur
