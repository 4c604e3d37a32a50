// Shapes the simulated cell checks for contact: the daemon's own
// (robot_client/collision: oriented boxes, the arm's links as capsules,
// FCL's exact tests) plus the overlap depth the cell tolerates between
// boxes, from the separating-axis test the scene generator places boxes
// with (tests/support/obb.h).
#pragma once

#include "robot_client/collision/arm_capsules.h"
#include "robot_client/collision/shapes.h"

namespace cornerpose::cell_sim {

using collision::Aabb;
using collision::ArmCapsules;
using collision::BoundsOf;
using collision::Capsule;
using collision::CapsuleTouchesBox;
using collision::Obb;
using collision::ToolShape;

// True when the boxes overlap by more than `tolerance_m` (touching faces
// and overlaps up to the tolerance are contact, not collision).
bool BoxesOverlap(const Obb& a, const Obb& b, double tolerance_m);
// The lowest point of the box, world z.
double LowestZ(const Obb& box);

}  // namespace cornerpose::cell_sim
