// Oriented-box geometry used to place boxes without interpenetration.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>

#include "common/perception/types.h"

namespace cornerpose::testing {

// The 8 corners of a box in the frame of pose (world_T_box).
std::array<Eigen::Vector3d, 8> BoxCorners(const BoxDims& dims, const Eigen::Isometry3d& pose);

// Separating-axis test over the 15 candidate axes. Returns the largest gap
// along any axis: > 0 the boxes are apart (a lower bound on their distance),
// 0 they touch, < 0 they overlap by at least that much along every axis.
double ObbSeparation(const BoxDims& a, const Eigen::Isometry3d& world_T_a, const BoxDims& b,
                     const Eigen::Isometry3d& world_T_b);

}  // namespace cornerpose::testing
