// The surface a depth image measures at a point near a face's plane.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <limits>
#include <optional>

#include "common/perception/camera_model.h"

namespace cornerpose::internal {

// The surface measured where point q (on or near a face's plane) projects:
// its height above the plane along `normal` (NaN where the pixel has no
// return), or nothing when q is behind the camera or out of view.
inline std::optional<double> HeightAt(const DepthImage& depth, const Eigen::Vector3d& q,
                                      const Eigen::Vector3d& normal) {
  if (q.z() <= 0.05) return std::nullopt;
  const Eigen::Vector2d px = Project(depth.camera, q);
  const int u = static_cast<int>(std::lround(px.x())), v = static_cast<int>(std::lround(px.y()));
  if (!depth.inside(u, v)) return std::nullopt;
  const float z = depth.at(u, v);
  if (std::isnan(z)) return std::numeric_limits<double>::quiet_NaN();
  return (z * PixelRay(depth.camera, u, v) - q).dot(normal);
}

}  // namespace cornerpose::internal
