// A box on the floor lies on it. The grasp face's plane is fitted to its
// pixels; on an active stereo camera the depth of a face a few centimetres
// wide (a brick's 9 cm) is smoothed with what lies beside it, and its fit
// comes out tilted by 5-10 degrees about the face's long axis. Turned so,
// a box resting on the floor reaches into the floor at one side of its
// bottom and lifts off it at the other: no box can lie so. A returned box
// whose bottom face (the face nearest to lying on the floor's plane, within
// max_tilt_deg) dips at least min_dip_m into the floor and has every
// corner within max_gap_m of it once turned flat onto it is turned so,
// about its grasp face centre (pose only; no box added or dropped). Boxes
// on other boxes, or leaning with one edge on the floor (every corner above
// it), keep their pose. Applied after the layer rules (layer_plane.h,
// layer_turn.h).
#pragma once

#include <Eigen/Core>
#include <vector>

#include "absl/status/status.h"
#include "common/perception/types.h"

namespace cornerpose {

struct FloorRestOptions {
  // A box is turned only when its bottom is tilted against the floor by at
  // most this (more is not a fit's error). 12 in session 33: a stereo brick
  // in a heap, its 9 cm face fitted 12.5 degrees off on the noise, its
  // bottom in the floor, kept its pose. Degrees, [0, 30]; 0 turns the rule
  // off.
  double max_tilt_deg = 15.0;
  // ... and by more than this (less is within the fit's noise).
  // Degrees, [0, 30].
  double min_tilt_deg = 1.0;
  // How far the deepest corner of its bottom must reach into the floor (a
  // box on the floor, not above it, nor leaning on one edge of its bottom:
  // that corner lies on the floor, within the fit's noise). 4 mm until
  // session 36: a stereo brick fitted 5.4 degrees off dipped 2.7 mm and kept
  // its pose; at 1 mm 71 boxes of the 94 generated sets turned, every one
  // nearer its true pose (rotation error 2.7 -> 0.8 degrees on average),
  // none further. Metres, [0, 0.1].
  double min_dip_m = 0.001;
  // Turned flat about its grasp face centre, every corner of its bottom
  // must lie within this of the floor's plane (it rests on the floor).
  // Metres, (0, 0.1].
  double max_gap_m = 0.02;

  absl::Status Validate() const;
};

// Turns the boxes of *boxes that rest on the floor (floor_normal towards
// the camera, floor_point on it) flat onto it. Returns how many turned.
int RestOnFloor(const Eigen::Vector3d& floor_normal, const Eigen::Vector3d& floor_point,
                const BoxDims& dims, const FloorRestOptions& options,
                std::vector<DetectedBox>* boxes);

}  // namespace cornerpose
