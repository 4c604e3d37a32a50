// The arm as capsules for contact checks: one per link of a UR5 / UR5e,
// placed through the same DH chain as the kinematics (robot_client/ur), with
// the links' lateral offsets and radii from UR's published dimensions. A
// coarse envelope (the real links are tubes and joint housings), good to a
// centimetre or two.
#pragma once

#include <Eigen/Geometry>
#include <vector>

#include "robot_client/collision/shapes.h"
#include "robot_client/ur/kinematics.h"

namespace cornerpose::collision {

struct ToolShape {
  // The suction tool from the flange to its tip, a capsule of this radius, m.
  double radius_m = 0.03;
  // The last part of the tool, the compliant cup, may press this far into
  // what it touches without counting as contact, m (>= 0).
  double cup_compliance_m = 0.01;
};

// Capsules in the base frame for joints q: base, shoulder, upper arm,
// forearm, wrists 1-3 and the tool up to flange_T_tcp (minus the cup's
// compliance). Names: "base", "shoulder", "upper_arm", "forearm",
// "wrist_1", "wrist_2", "wrist_3", "tool".
std::vector<Capsule> ArmCapsules(ur::ArmModel model, const ur::Joints& q,
                                 const Eigen::Isometry3d& flange_T_tcp, const ToolShape& tool);

}  // namespace cornerpose::collision
