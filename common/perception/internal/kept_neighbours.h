// Whether a side of a hypothesis's grasp face lies against a box already
// kept: a seam the depth does not show, which the kept box vouches for.
#pragma once

#include <Eigen/Geometry>
#include <vector>

#include "common/box/box_types.h"

namespace cornerpose::internal {

// True when side `side` (RefinementResult::sides' index: +a, -a, +b, -b) of
// the grasp face of the box at camera_T_box lies against the grasp face of
// a box in `kept`: on three points along the side (at 0 and ±30 % of its
// length), the face 2 cm past the side lies on a kept box's grasp face (its
// plane within 1.5 cm and 8°, at least 5 mm inside its outline) and 2 cm
// before the side does not, and that box's sides run along this one within
// 5°. In a layer of touching boxes, the side is where that box ends.
bool SideAgainstKeptBox(const Eigen::Isometry3d& camera_T_box, BoxFace grasp, const BoxDims& dims,
                        int side, const std::vector<DetectedBox>& kept);

}  // namespace cornerpose::internal
