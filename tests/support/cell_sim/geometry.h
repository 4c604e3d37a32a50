// Shapes the simulated cell checks for contact: oriented boxes (cartons,
// pallet boards, walls) and capsules (the arm's links), and the two tests
// between them. Capsule-box contact uses FCL (Debian's libfcl-dev), kept out
// of this header; box-box contact is the separating-axis test the scene
// generator places boxes with (tests/support/obb.h).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>

#include "common/perception/types.h"

namespace cornerpose::cell_sim {

struct Obb {
  BoxDims dims;
  Eigen::Isometry3d world_T_box = Eigen::Isometry3d::Identity();
};

// A segment a-b swept by a sphere of `radius`.
struct Capsule {
  std::string name;
  Eigen::Vector3d a = Eigen::Vector3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  double radius = 0.0;
};

// Axis-aligned bounds, for a cheap first test before the exact one.
struct Aabb {
  Eigen::Vector3d min = Eigen::Vector3d::Constant(1e9);
  Eigen::Vector3d max = Eigen::Vector3d::Constant(-1e9);
  bool Overlaps(const Aabb& o) const {
    return (min.array() <= o.max.array()).all() && (o.min.array() <= max.array()).all();
  }
  bool Contains(const Eigen::Vector3d& p) const {
    return (p.array() >= min.array()).all() && (p.array() <= max.array()).all();
  }
};
Aabb BoundsOf(const Obb& box);
Aabb BoundsOf(const Capsule& capsule);

// True when the capsule and the box share a point.
bool CapsuleTouchesBox(const Capsule& capsule, const Obb& box);
// True when the boxes overlap by more than `tolerance_m` (touching faces
// and overlaps up to the tolerance are contact, not collision).
bool BoxesOverlap(const Obb& a, const Obb& b, double tolerance_m);
// The lowest point of the box, world z.
double LowestZ(const Obb& box);

}  // namespace cornerpose::cell_sim
