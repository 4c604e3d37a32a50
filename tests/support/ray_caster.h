// Exact ray casting of cuboids and the floor (slab method), the geometric
// core of the scene generator. Internal to tests/support.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <limits>
#include <vector>

#include "tests/support/scene_generator.h"

namespace cornerpose::testing::internal {

// Screen-space bounds of a projected cuboid, continuous pixel coordinates.
struct Rect {
  double u0 = -std::numeric_limits<double>::infinity();
  double u1 = std::numeric_limits<double>::infinity();
  double v0 = -std::numeric_limits<double>::infinity();
  double v1 = std::numeric_limits<double>::infinity();
  bool Contains(double u, double v) const { return u >= u0 && u <= u1 && v >= v0 && v <= v1; }
  bool bounded() const { return std::isfinite(u0) && std::isfinite(u1); }
};

// A box or support part in the camera frame.
struct Cuboid {
  Eigen::Vector3d half;
  Eigen::Matrix3d cam_R_box;
  Eigen::Vector3d cam_t_box;
  Eigen::Vector3d camera_in_box;  // camera centre in the box frame
  Rect camera_rect;               // where rays can hit it
  Rect projector_rect;            // same, seen from the projector
  Eigen::Vector3d lo, hi;         // axis-aligned bounds in the camera frame
};

inline constexpr int kNothing = -1;
inline constexpr int kFloor = -2;

struct Hit {
  double depth = std::numeric_limits<double>::infinity();  // camera z, m
  int object = kNothing;                                   // kNothing, kFloor, or a cuboid index
  int face = -1;                                           // BoxFace of a cuboid hit
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();        // camera frame, outward
};

// Cuboids are the scene's boxes (indices 0..n-1) followed by its supports.
class RayCaster {
 public:
  RayCaster(const Scene& scene, double projector_offset_m);

  // Camera-frame ray with z = 1 through continuous pixel (u, v).
  Eigen::Vector3d Ray(double u, double v) const {
    return {(u - camera_.cx) / camera_.fx, (v - camera_.cy) / camera_.fy, 1.0};
  }
  // Nearest surface along the ray through (u, v).
  Hit Cast(double u, double v) const;
  // Cuboid i alone, no floor.
  Hit CastCuboid(int i, double u, double v) const;
  // True when the segment from a surface point to the projector crosses a
  // cuboid other than `skip`.
  bool ProjectorBlocked(const Eigen::Vector3d& point, int skip) const;
  // True when origin + t dir, t in (0, max_t], crosses any cuboid (shadow and
  // occlusion rays of the colour rendering). The floor never occludes.
  bool Occluded(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double max_t) const;

  const Eigen::Vector3d& projector() const { return projector_; }
  const std::vector<Cuboid>& cuboids() const { return cuboids_; }
  int num_boxes() const { return num_boxes_; }
  // a x + b y + c z + d = 0 in the camera frame, normal towards the camera.
  const Eigen::Vector4d& floor_plane() const { return floor_plane_; }

 private:
  bool HitCuboid(int i, const Eigen::Vector3d& ray, Hit* hit) const;

  CameraIntrinsics camera_;
  Eigen::Vector3d projector_;
  std::vector<Cuboid> cuboids_;
  int num_boxes_ = 0;
  bool floor_ = true;
  Eigen::Vector4d floor_plane_ = Eigen::Vector4d::Zero();
};

}  // namespace cornerpose::testing::internal
