#include "robot_client/collision/shapes.h"

#include <fcl/geometry/shape/box.h>
#include <fcl/geometry/shape/capsule.h>
#include <fcl/narrowphase/collision.h>

namespace cornerpose::collision {
namespace {

fcl::Transform3d FclPose(const Eigen::Isometry3d& pose) {
  fcl::Transform3d tf = fcl::Transform3d::Identity();
  tf.linear() = pose.linear();
  tf.translation() = pose.translation();
  return tf;
}

}  // namespace

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
  fcl::CollisionRequestd request;
  fcl::CollisionResultd result;
  fcl::collide(&capsule_shape, capsule_tf, &box_shape, FclPose(box.world_T_box), request, result);
  return result.isCollision();
}

bool BoxesTouch(const Obb& a, const Obb& b) {
  if (!BoundsOf(a).Overlaps(BoundsOf(b))) return false;
  const fcl::Boxd a_shape(a.dims.l, a.dims.b, a.dims.h);
  const fcl::Boxd b_shape(b.dims.l, b.dims.b, b.dims.h);
  fcl::CollisionRequestd request;
  fcl::CollisionResultd result;
  fcl::collide(&a_shape, FclPose(a.world_T_box), &b_shape, FclPose(b.world_T_box), request, result);
  return result.isCollision();
}

Obb Inflated(const Obb& box, double margin_m) {
  Obb out = box;
  out.dims.l += 2.0 * margin_m;
  out.dims.b += 2.0 * margin_m;
  out.dims.h += 2.0 * margin_m;
  return out;
}

}  // namespace cornerpose::collision
