#include "robot_client/planning/straight_move.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "absl/strings/str_format.h"

namespace cornerpose::robot_client {
namespace {

// start_joints must put the TCP at from_tcp within this (IK reproduces poses
// to 1e-6).
constexpr double kStartToleranceM = 1e-4;
constexpr double kStartToleranceRad = 1e-4;

std::string Xyz(const Eigen::Vector3d& p) {
  return absl::StrFormat("(%.3f, %.3f, %.3f)", p.x(), p.y(), p.z());
}

bool Positive(double v) { return std::isfinite(v) && v > 0.0; }

}  // namespace

absl::Status CheckStraightMove(ur::ArmModel model, const Eigen::Isometry3d& flange_T_tcp,
                               const ur::Joints& start_joints, const Eigen::Isometry3d& from_tcp,
                               const Eigen::Isometry3d& to_tcp, const StraightMoveOptions& options,
                               ur::Joints* end_joints) {
  if (!Positive(options.step_m) || !Positive(options.step_rad) ||
      !Positive(options.linear_speed_m_s) || !Positive(options.angular_speed_rad_s) ||
      !Positive(options.max_joint_speed_rad_s)) {
    return absl::InvalidArgumentError(
        "straight move options: steps, speeds and the joint speed must be finite and > 0");
  }
  const Eigen::Isometry3d start_tcp = ur::ForwardKinematics(model, start_joints) * flange_T_tcp;
  const Eigen::Quaterniond r0(from_tcp.linear());
  const Eigen::Quaterniond r1(to_tcp.linear());
  if (!from_tcp.matrix().allFinite() || !to_tcp.matrix().allFinite() ||
      (start_tcp.translation() - from_tcp.translation()).norm() > kStartToleranceM ||
      ur::RotationAngleBetween(Eigen::Quaterniond(start_tcp.linear()), r0) > kStartToleranceRad) {
    return absl::InvalidArgumentError(
        absl::StrFormat("straight move from %s: the start joints put the TCP at %s",
                        Xyz(from_tcp.translation()), Xyz(start_tcp.translation())));
  }

  const Eigen::Vector3d p0 = from_tcp.translation();
  const Eigen::Vector3d p1 = to_tcp.translation();
  const double length = (p1 - p0).norm();
  const double angle = ur::RotationAngleBetween(r0, r1);
  const int samples = std::max(
      1, static_cast<int>(std::ceil(std::max(length / options.step_m, angle / options.step_rad))));
  const double ds = length / samples;
  const double dtheta = angle / samples;
  // The floor keeps a null move (IK rounding only) from failing.
  const double max_step = std::max(
      1e-6, options.max_joint_speed_rad_s *
                std::max(ds / options.linear_speed_m_s, dtheta / options.angular_speed_rad_s));
  const Eigen::Isometry3d tcp_T_flange = flange_T_tcp.inverse();

  ur::Joints previous = start_joints;
  for (int k = 1; k <= samples; ++k) {
    const double s = static_cast<double>(k) / samples;
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.translation() = p0 + s * (p1 - p0);
    pose.linear() = r0.slerp(s, r1).toRotationMatrix();
    absl::StatusOr<ur::Joints> q = ur::InverseKinematics(model, pose * tcp_T_flange, previous);
    if (!q.ok()) {
      return absl::FailedPreconditionError(
          absl::StrFormat("leaves the arm's reach at %s", Xyz(pose.translation())));
    }
    for (int i = 0; i < 6; ++i) {
      const double change = std::abs((*q)[i] - previous[i]);
      if (change > max_step) {
        return absl::FailedPreconditionError(absl::StrFormat(
            "passes a singularity at %s: joint %d would turn %.3f rad in %.1f mm (max %.3f)",
            Xyz(pose.translation()), i + 1, change, 1e3 * ds, max_step));
      }
    }
    previous = *q;
  }
  if (end_joints != nullptr) *end_joints = previous;
  return absl::OkStatus();
}

}  // namespace cornerpose::robot_client
