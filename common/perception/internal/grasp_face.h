// A returned box's grasp face in the camera frame, and the tests the layer
// rules (layer_plane.h, layer_turn.h) group faces by.
#pragma once

#include <Eigen/Core>
#include <cmath>

#include "common/perception/types.h"

namespace cornerpose::internal {

struct GraspFace {
  Eigen::Vector3d c, n, a, b;  // centre, outward normal, in-plane axes (unit)
  double half_a = 0.0, half_b = 0.0;
};

inline GraspFace GraspFaceOf(const DetectedBox& box, const BoxDims& dims) {
  const int fi = static_cast<int>(box.grasp_face);
  const int axis_n = fi / 2, axis_a = (axis_n + 1) % 3, axis_b = (axis_n + 2) % 3;
  GraspFace f;
  f.c = box.grasp_centre_camera;
  f.n = box.grasp_normal_camera.normalized();
  f.a = box.camera_T_box.linear().col(axis_a);
  f.b = box.camera_T_box.linear().col(axis_b);
  f.half_a = dims[axis_a] / 2.0;
  f.half_b = dims[axis_b] / 2.0;
  return f;
}

// Centres closer than touch_factor times the sum of the half diagonals.
inline bool FacesTouch(const GraspFace& x, const GraspFace& y, double touch_factor) {
  return (x.c - y.c).norm() <=
         touch_factor * (std::hypot(x.half_a, x.half_b) + std::hypot(y.half_a, y.half_b));
}

// Normals within acos(cos_max) and each centre within tolerance_m of the
// other's plane.
inline bool FacesOnOnePlane(const GraspFace& x, const GraspFace& y, double cos_max,
                            double tolerance_m) {
  return x.n.dot(y.n) >= cos_max && std::abs((y.c - x.c).dot(x.n)) <= tolerance_m &&
         std::abs((x.c - y.c).dot(y.n)) <= tolerance_m;
}

}  // namespace cornerpose::internal
