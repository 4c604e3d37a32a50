// How much of a box the camera's image holds: the share of its outline
// (the convex hull of its eight corners projected) that lies inside the
// image. A box partly out of view has a part that cannot be checked for
// what touches it, and its pose rests on less of it.
#pragma once

#include <Eigen/Geometry>

#include "common/perception/types.h"

namespace cornerpose::internal {

// In [0, 1]: 1 for a box wholly in view, 0 for one out of view or with a
// corner not in front of the camera (z <= 5 cm).
double BoxViewShare(const CameraIntrinsics& camera, const Eigen::Isometry3d& camera_T_box,
                    const BoxDims& dims);

}  // namespace cornerpose::internal
