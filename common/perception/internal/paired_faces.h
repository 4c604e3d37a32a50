// Two boxes read side by side on the same face whose faces together are
// another face of the box: the one box they may be.
#pragma once

#include <Eigen/Geometry>
#include <optional>

#include "common/box/box_types.h"

namespace cornerpose::internal {

// When boxes `x` and `y` lie side by side on one plane (grasp normals within
// 8°, each centre within 1.5 cm of the other's plane), read on the same face
// with their sides aligned (within 5°), one face width apart along one of
// its axes and in line along the other (within tolerance_m), and the
// rectangle they cover together is another face of the box (its two sides
// within tolerance_m): the pose of one box on that face, the rectangle its
// grasp face, its normal theirs. A carton whose height is half its width
// has a top that its flap seam splits into two faces the size of its side:
// read so, it is two cartons on their side. Otherwise nullopt.
std::optional<Eigen::Isometry3d> OneBoxForPair(const DetectedBox& x, const DetectedBox& y,
                                               const BoxDims& dims, double tolerance_m);

}  // namespace cornerpose::internal
