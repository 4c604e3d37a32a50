// Shapes for contact checks, shared by the daemon's planner and the
// simulated cell: oriented boxes (cartons, pallet loads, walls), capsules
// (the arm's links) and axis-aligned bounds. The exact tests run through FCL
// (Debian's libfcl-dev), kept out of this header.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>

#include "common/box/box_types.h"

namespace cornerpose::collision {

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
// True when the boxes share a point (FCL's box-box test).
bool BoxesTouch(const Obb& a, const Obb& b);
// The box grown by `margin_m` on every side (its dims by 2 * margin).
Obb Inflated(const Obb& box, double margin_m);

}  // namespace cornerpose::collision
