// A grasp face the image border cuts on one side: whether what is in view
// pins the box down.
#pragma once

#include <Eigen/Geometry>

#include "common/box/box_types.h"
#include "common/perception/box_refinement.h"
#include "common/perception/camera_model.h"
#include "common/perception/detector.h"

namespace cornerpose::internal {

// The side of the grasp face (RefinementResult::sides' index: +a, -a, +b,
// -b) that lies out of view and is pinned by what is in view, or -1. A face
// is pinned up to the border when the refinement measured its three other
// sides (free or a seam), the fourth is unseen and lies past the image
// border (AcceptanceOptions::border_margin_px), on three lines along it
// the face is seen on its plane (RefinementOptions::plane_tolerance_m)
// from its measured end to the border for at least min_in_view_share of
// its length (where a gripper aims, the face's centre, is in view), and on
// one of them for longer than any shorter side of the box that could stand
// there (extent_tolerance_m more: then it is no other face of the box; the
// border may cut the face aslant, and the measured sides fix its turn).
// With border_band_ends_view, a line's view ends where a run of pixels
// with no return reaches the border (an active stereo camera's band). A longer side of
// the box that could stand there (the face may go on out of view) leaves it
// unpinned. With the box's size known, the measured end and the face's
// size then say where the face ends out of view.
int SideOutOfViewPinned(const DepthImage& depth, const Eigen::Isometry3d& camera_T_box,
                        BoxFace grasp, const BoxDims& dims, const RefinementResult& ref,
                        const AcceptanceOptions& o, double plane_tolerance_m);

}  // namespace cornerpose::internal
