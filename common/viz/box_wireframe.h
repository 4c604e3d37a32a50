// The corners and the 12 edges of a detected box, in the camera frame; shared
// by the PLY and PNG writers.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <utility>

#include "common/perception/types.h"

namespace cornerpose {

// Corner i sits at (+-l/2, +-b/2, +-h/2) in the box frame, with bit 0 of i
// choosing the sign of x, bit 1 of y and bit 2 of z (set = plus).
std::array<Eigen::Vector3d, 8> BoxCornersCamera(const Eigen::Isometry3d& camera_T_box,
                                                const BoxDims& dims);

// The 12 edges as pairs of corner indices (corners that differ in one bit).
const std::array<std::pair<int, int>, 12>& BoxEdges();

}  // namespace cornerpose
