#include "tests/support/cell_sim/geometry.h"

#include <fcl/geometry/shape/box.h>
#include <fcl/geometry/shape/capsule.h>
#include <fcl/narrowphase/collision.h>

#include "tests/support/obb.h"

namespace cornerpose::cell_sim {

Aabb BoundsOf(const Obb& box) {
  // Half extent along each world axis: |R| * half.
  const Eigen::Vector3d half = 0.5 * box.dims.vec();
  const Eigen::Vector3d extent = box.world_T_box.linear().cwiseAbs() * half;
  return {box.world_T_box.translation() - extent, box.world_T_box.translation() + extent};
}

Aabb BoundsOf(const Capsule& c) {
  const Eigen::Vector3d r = Eigen::Vector3d::Constant(c.radius);
  return {c.a.cwiseMin(c.b) - r, c.a.cwiseMax(c.b) + r};
}

bool CapsuleTouchesBox(const Capsule& capsule, const Obb& box) {
  if (!BoundsOf(capsule).Overlaps(BoundsOf(box))) return false;
  const Eigen::Vector3d axis = capsule.b - capsule.a;
  const double length = axis.norm();
  // FCL's capsule is centred on its frame's origin along z.
  fcl::Transform3d capsule_tf = fcl::Transform3d::Identity();
  capsule_tf.translation() = 0.5 * (capsule.a + capsule.b);
  if (length > 1e-9) {
    capsule_tf.linear() =
        Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), axis / length)
            .toRotationMatrix();
  }
  const fcl::Capsuled capsule_shape(capsule.radius, length);
  const fcl::Boxd box_shape(box.dims.l, box.dims.b, box.dims.h);
  fcl::Transform3d box_tf = fcl::Transform3d::Identity();
  box_tf.linear() = box.world_T_box.linear();
  box_tf.translation() = box.world_T_box.translation();
  fcl::CollisionRequestd request;
  fcl::CollisionResultd result;
  fcl::collide(&capsule_shape, capsule_tf, &box_shape, box_tf, request, result);
  return result.isCollision();
}

bool BoxesOverlap(const Obb& a, const Obb& b, double tolerance_m) {
  if (!BoundsOf(a).Overlaps(BoundsOf(b))) return false;
  return testing::ObbSeparation(a.dims, a.world_T_box, b.dims, b.world_T_box) < -tolerance_m;
}

double LowestZ(const Obb& box) { return BoundsOf(box).min.z(); }

}  // namespace cornerpose::cell_sim
