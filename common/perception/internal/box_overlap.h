// Separating-axis test between two oriented boxes of the same size.
#pragma once

#include <Eigen/Geometry>

#include "common/perception/types.h"

namespace cornerpose::internal {

// True when the two boxes, each shrunk by `margin_m` on every side, intersect.
inline bool BoxesOverlap(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b,
                         const BoxDims& dims, double margin_m) {
  const Eigen::Vector3d half =
      (0.5 * dims.vec() - Eigen::Vector3d::Constant(margin_m)).cwiseMax(1e-4);
  const Eigen::Matrix3d Ra = a.linear(), Rb = b.linear();
  const Eigen::Vector3d t = b.translation() - a.translation();
  auto separated = [&](const Eigen::Vector3d& axis) {
    if (axis.squaredNorm() < 1e-10) return false;
    const Eigen::Vector3d n = axis.normalized();
    double ra = 0.0, rb = 0.0;
    for (int i = 0; i < 3; ++i) {
      ra += half[i] * std::abs(Ra.col(i).dot(n));
      rb += half[i] * std::abs(Rb.col(i).dot(n));
    }
    return std::abs(t.dot(n)) > ra + rb;
  };
  for (int i = 0; i < 3; ++i) {
    if (separated(Ra.col(i)) || separated(Rb.col(i))) return false;
    for (int j = 0; j < 3; ++j) {
      if (separated(Ra.col(i).cross(Rb.col(j)))) return false;
    }
  }
  return true;
}

}  // namespace cornerpose::internal
