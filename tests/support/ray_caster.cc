#include "tests/support/ray_caster.h"

#include <algorithm>
#include <cmath>

#include "tests/support/obb.h"

namespace cornerpose::testing::internal {
namespace {

// Entry and exit of the line o + t d through the axis-aligned box [-h, h];
// false when they miss. axis_in is the axis of the entry face.
bool Slab(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Eigen::Vector3d& h,
          double* t_in, double* t_out, int* axis_in) {
  double lo = -std::numeric_limits<double>::infinity();
  double hi = std::numeric_limits<double>::infinity();
  int axis = -1;
  for (int i = 0; i < 3; ++i) {
    if (std::abs(d[i]) < 1e-15) {
      if (std::abs(o[i]) > h[i]) return false;
      continue;
    }
    const double inv = 1.0 / d[i];
    double t0 = (-h[i] - o[i]) * inv;
    double t1 = (h[i] - o[i]) * inv;
    if (t0 > t1) std::swap(t0, t1);
    if (t0 > lo) {
      lo = t0;
      axis = i;
    }
    hi = std::min(hi, t1);
    if (lo > hi) return false;
  }
  *t_in = lo;
  *t_out = hi;
  *axis_in = axis;
  return true;
}

// Bounds of the cuboid's corners projected from a pinhole at `centre` with
// the camera's orientation; unbounded when a corner is not in front.
Rect ProjectedRect(const std::array<Eigen::Vector3d, 8>& corners, const Eigen::Vector3d& centre,
                   const CameraIntrinsics& camera) {
  Rect rect{std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
            std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()};
  for (const Eigen::Vector3d& corner : corners) {
    const Eigen::Vector3d q = corner - centre;
    if (q.z() < 1e-3) return Rect{};
    const double u = camera.fx * q.x() / q.z() + camera.cx;
    const double v = camera.fy * q.y() / q.z() + camera.cy;
    rect.u0 = std::min(rect.u0, u);
    rect.u1 = std::max(rect.u1, u);
    rect.v0 = std::min(rect.v0, v);
    rect.v1 = std::max(rect.v1, v);
  }
  // A hair of slack so rays grazing a silhouette corner are not culled.
  rect.u0 -= 1e-6;
  rect.v0 -= 1e-6;
  rect.u1 += 1e-6;
  rect.v1 += 1e-6;
  return rect;
}

}  // namespace

RayCaster::RayCaster(const Scene& scene, double projector_offset_m)
    : camera_(scene.camera),
      projector_(projector_offset_m, 0.0, 0.0),
      num_boxes_(static_cast<int>(scene.boxes.size())),
      floor_(scene.floor) {
  const Eigen::Isometry3d camera_T_world = scene.world_T_camera.inverse();
  auto add = [&](const BoxDims& dims, const Eigen::Isometry3d& world_T_box) {
    Cuboid c;
    const Eigen::Isometry3d camera_T_box = camera_T_world * world_T_box;
    c.half = 0.5 * dims.vec();
    c.cam_R_box = camera_T_box.linear();
    c.cam_t_box = camera_T_box.translation();
    c.camera_in_box = -c.cam_R_box.transpose() * c.cam_t_box;
    const auto corners = BoxCorners(dims, camera_T_box);
    c.camera_rect = ProjectedRect(corners, Eigen::Vector3d::Zero(), camera_);
    c.projector_rect = ProjectedRect(corners, projector_, camera_);
    c.lo = c.hi = corners[0];
    for (const Eigen::Vector3d& corner : corners) {
      c.lo = c.lo.cwiseMin(corner);
      c.hi = c.hi.cwiseMax(corner);
    }
    cuboids_.push_back(c);
  };
  for (const SceneBox& box : scene.boxes) add(box.dims, box.world_T_box);
  for (const SupportPart& part : scene.supports) add(part.dims, part.world_T_part);

  // World z of a camera point p is n.p + camera height, n = world z in camera.
  const Eigen::Vector3d n = camera_T_world.linear().col(2);
  const double height = scene.world_T_camera.translation().z();
  floor_plane_ << n, height;
  if (height < 0) floor_plane_ = -floor_plane_;
}

bool RayCaster::HitCuboid(int i, const Eigen::Vector3d& ray, Hit* hit) const {
  const Cuboid& c = cuboids_[i];
  const Eigen::Vector3d d = c.cam_R_box.transpose() * ray;
  double t_in, t_out;
  int axis;
  if (!Slab(c.camera_in_box, d, c.half, &t_in, &t_out, &axis)) return false;
  if (t_in <= 0.0 || axis < 0 || t_in >= hit->depth) return false;
  const bool plus = d[axis] < 0.0;  // entering through the +axis face
  hit->depth = t_in;
  hit->object = i;
  hit->face = 2 * axis + (plus ? 0 : 1);
  hit->normal = c.cam_R_box.col(axis) * (plus ? 1.0 : -1.0);
  return true;
}

Hit RayCaster::Cast(double u, double v) const {
  Hit hit;
  const Eigen::Vector3d ray = Ray(u, v);
  if (floor_) {
    const double denom = floor_plane_.head<3>().dot(ray);
    if (denom < 0.0) {  // the plane's normal faces the camera
      const double t = -floor_plane_[3] / denom;
      if (t > 0.0) {
        hit.depth = t;
        hit.object = kFloor;
        hit.normal = floor_plane_.head<3>();
      }
    }
  }
  for (int i = 0; i < static_cast<int>(cuboids_.size()); ++i) {
    if (cuboids_[i].camera_rect.Contains(u, v)) HitCuboid(i, ray, &hit);
  }
  return hit;
}

Hit RayCaster::CastCuboid(int i, double u, double v) const {
  Hit hit;
  if (cuboids_[i].camera_rect.Contains(u, v)) HitCuboid(i, Ray(u, v), &hit);
  return hit;
}

bool RayCaster::ProjectorBlocked(const Eigen::Vector3d& point, int skip) const {
  const Eigen::Vector3d q = point - projector_;
  if (q.z() <= 0.0) return false;
  const double u = camera_.fx * q.x() / q.z() + camera_.cx;
  const double v = camera_.fy * q.y() / q.z() + camera_.cy;
  const Eigen::Vector3d seg = projector_ - point;
  for (int i = 0; i < static_cast<int>(cuboids_.size()); ++i) {
    const Cuboid& c = cuboids_[i];
    if (i == skip || !c.projector_rect.Contains(u, v)) continue;
    const Eigen::Vector3d o = c.cam_R_box.transpose() * (point - c.cam_t_box);
    const Eigen::Vector3d d = c.cam_R_box.transpose() * seg;
    double t_in, t_out;
    int axis;
    if (!Slab(o, d, c.half, &t_in, &t_out, &axis)) continue;
    // The segment is t in (0, 1); a point resting on this cuboid touches it
    // only at t ~ 0, which must not count.
    if (t_out > 1e-7 && t_in < 1.0 && t_out - std::max(t_in, 0.0) > 1e-9) return true;
  }
  return false;
}

bool RayCaster::Occluded(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
                         double max_t) const {
  for (const Cuboid& c : cuboids_) {
    // Bounds first: most cuboids are nowhere near the ray.
    double t_in, t_out;
    int axis;
    const Eigen::Vector3d centre = 0.5 * (c.lo + c.hi), half = 0.5 * (c.hi - c.lo);
    if (!Slab(origin - centre, dir, half, &t_in, &t_out, &axis)) continue;
    if (t_out <= 1e-9 || t_in > max_t) continue;
    const Eigen::Vector3d o = c.cam_R_box.transpose() * (origin - c.cam_t_box);
    const Eigen::Vector3d d = c.cam_R_box.transpose() * dir;
    if (!Slab(o, d, c.half, &t_in, &t_out, &axis)) continue;
    if (t_out > 1e-9 && t_in < max_t) return true;
  }
  return false;
}

}  // namespace cornerpose::testing::internal
