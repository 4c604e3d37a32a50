#include "robot_client/collision/arm_capsules.h"

#include <array>

namespace cornerpose::collision {
namespace {

// Offsets of the upper arm and forearm from the DH plane along the joint
// axes (the DH table folds them into d4), and link radii, metres: from UR's
// published link drawings (UR5e: shoulder offset 0.138, elbow -0.131; UR5:
// 0.13585, -0.1197).
struct LinkSizes {
  double shoulder_offset, forearm_offset;
  double base_r, shoulder_r, upper_arm_r, forearm_r, wrist_r;
};

LinkSizes SizesOf(ur::ArmModel model) {
  if (model == ur::ArmModel::kUr5) return {0.13585, 0.01615, 0.075, 0.06, 0.054, 0.045, 0.045};
  return {0.138, 0.007, 0.075, 0.06, 0.054, 0.045, 0.045};
}

Eigen::Isometry3d Dh(double a, double d, double alpha, double theta) {
  return Eigen::Isometry3d(Eigen::AngleAxisd(theta, Eigen::Vector3d::UnitZ())) *
         Eigen::Translation3d(0, 0, d) * Eigen::Translation3d(a, 0, 0) *
         Eigen::AngleAxisd(alpha, Eigen::Vector3d::UnitX());
}

}  // namespace

std::vector<Capsule> ArmCapsules(ur::ArmModel model, const ur::Joints& q,
                                 const Eigen::Isometry3d& flange_T_tcp, const ToolShape& tool) {
  const ur::DhParameters& dh = ur::NominalDh(model);
  std::array<Eigen::Isometry3d, 7> frame;
  frame[0] = Eigen::Isometry3d::Identity();
  for (int i = 0; i < 6; ++i) frame[i + 1] = frame[i] * Dh(dh.a[i], dh.d[i], dh.alpha[i], q[i]);
  auto origin = [&](int i) { return Eigen::Vector3d(frame[i].translation()); };
  auto z_axis = [&](int i) { return Eigen::Vector3d(frame[i].linear().col(2)); };
  const LinkSizes s = SizesOf(model);

  std::vector<Capsule> out;
  // Base: from just above the mounting plate (it stands on its pedestal)
  // up to the shoulder joint.
  out.push_back({"base", Eigen::Vector3d(0, 0, s.base_r), origin(1), s.base_r});
  const Eigen::Vector3d shoulder_side = origin(1) + s.shoulder_offset * z_axis(1);
  out.push_back({"shoulder", origin(1), shoulder_side, s.shoulder_r});
  out.push_back(
      {"upper_arm", shoulder_side, origin(2) + s.shoulder_offset * z_axis(2), s.upper_arm_r});
  out.push_back({"forearm", origin(2) + s.forearm_offset * z_axis(2),
                 origin(3) + s.forearm_offset * z_axis(3), s.forearm_r});
  out.push_back({"wrist_1", origin(3) + s.forearm_offset * z_axis(3), origin(4), s.wrist_r});
  out.push_back({"wrist_2", origin(4), origin(5), s.wrist_r});
  out.push_back({"wrist_3", origin(5), origin(6), s.wrist_r});
  // The tool: its rounded end stops cup_compliance short of the tip.
  const Eigen::Vector3d tip = frame[6] * flange_T_tcp.translation();
  const Eigen::Vector3d along = tip - origin(6);
  const double length = along.norm() - tool.cup_compliance_m - tool.radius_m;
  if (length > 1e-6) {
    out.push_back({"tool", origin(6), origin(6) + along.normalized() * length, tool.radius_m});
  }
  return out;
}

}  // namespace cornerpose::collision
