// UR5 (CB3) and UR5e kinematics: nominal DH parameters, forward kinematics to
// the tool flange and the closed-form inverse (up to 8 solutions), all in the
// controller's base frame (DH frame 0; ROS base_link is this rotated 180 deg
// about z). See shared/design/ur-interface.md section 4.
#pragma once

#include <Eigen/Geometry>
#include <array>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "robot_client/ur/pose.h"

namespace cornerpose::ur {

enum class ArmModel { kUr5, kUr5e };

// "ur5" or "ur5e", case-insensitive; INVALID_ARGUMENT otherwise.
absl::StatusOr<ArmModel> ParseArmModel(absl::string_view name);
// "ur5", "ur5e".
const char* ArmModelName(ArmModel model);

// Standard (distal) DH: T_i = Rz(theta_i) Tz(d_i) Tx(a_i) Rx(alpha_i), theta
// offsets 0. Metres and radians.
struct DhParameters {
  std::array<double, 6> a, d, alpha;
};

// The published nominal table (no per-robot calibration).
const DhParameters& NominalDh(ArmModel model);

// base_T_flange: the tool flange (no TCP offset) in the controller base frame.
Eigen::Isometry3d ForwardKinematics(const DhParameters& dh, const Joints& q);
Eigen::Isometry3d ForwardKinematics(ArmModel model, const Joints& q);

struct IkOptions {
  // A solution is kept only when FK reproduces the target within these.
  double position_tolerance_m = 1e-6;
  double rotation_tolerance_rad = 1e-6;
  // Joint range, symmetric: |q_i| <= joint_limit_rad (the UR5/UR5e range is
  // +-2 pi on every joint). Angles are shifted by multiples of 2 pi into this
  // range, nearest the seed.
  double joint_limit_rad = 2.0 * 3.14159265358979323846;
  // With sin(q5) ~ 0 (wrist singularity) q6 is free; this value is used.
  double singular_q6 = 0.0;
};

// All closed-form solutions for base_T_flange (up to 8), each angle in
// (-pi, pi], each verified with FK within options' tolerances. Empty when
// the pose is unreachable.
std::vector<Joints> InverseKinematicsAll(ArmModel model, const Eigen::Isometry3d& base_T_flange,
                                         const IkOptions& options = {});

// The solution nearest `seed` (Euclidean joint-space distance), each angle
// shifted by 2 pi multiples to the value within +-joint_limit_rad nearest the
// seed's. OUT_OF_RANGE when the pose is unreachable.
absl::StatusOr<Joints> InverseKinematics(ArmModel model, const Eigen::Isometry3d& base_T_flange,
                                         const Joints& seed, const IkOptions& options = {});

}  // namespace cornerpose::ur
