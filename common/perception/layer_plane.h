// Boxes side by side on one layer share its plane. A box's grasp face is
// fitted from its own pixels alone, and on an active-stereo camera the depth
// noise is correlated over blobs of ~10 pixels, so a brick's face 30 pixels
// across tilts by up to 9 degrees (generated D4xx frames: rms 3-5 degrees for
// bricks, 1-2.5 for cartons). Returned boxes whose grasp faces touch and lie
// in one plane (normals within max_angle_deg, each face's centre within
// plane_tolerance_m of the other's plane) are grouped; the group's plane is
// fitted through the interior pixels of all its faces (and must fit them
// about as well as each face's own plane does), and each box takes
// that plane's normal, turned about its own face centre: its in-plane turn
// and position stay its own. A face tilted further (up to adopt_angle_deg)
// that touches the group takes the plane when its pixels fit it about as
// well as their own (or, its centre so low on the plane that so tilted it
// would lie partly inside the layer, within a looser fit: rest_share); a
// box alone, or one whose pixels do not fit the plane (a carton sitting
// askew on the layer), keeps its own fit.
#pragma once

#include <vector>

#include "absl/status/status.h"
#include "common/perception/camera_model.h"
#include "common/perception/types.h"

namespace cornerpose {

struct LayerPlaneOptions {
  // Two faces are on one plane when their normals are within this and each
  // centre lies within plane_tolerance_m of the other face's plane; the
  // group's plane is taken by a box whose own normal is within this of it.
  // Degrees, [0, 30]; 0 turns the sharing off.
  double max_angle_deg = 12.0;
  // Metres, (0, 0.1].
  double plane_tolerance_m = 0.012;
  // Faces touch when their centres are closer than this share of the sum of
  // their half diagonals. Unitless, (0, 2].
  double touch_factor = 1.15;
  // Pixels nearer a face's side than this are not fitted (borders, seams).
  // Metres, [0, 0.1].
  double side_margin_m = 0.01;
  // A group shares a plane only when the points of all its faces lie about
  // it within this times (plus 1 mm) the rms of each face about its own.
  // Unitless, [1, 10].
  double max_rms_ratio = 1.3;
  // A face tilted further than max_angle_deg from a group's plane, up to
  // this, still takes it when it touches the group (a member, or a box
  // touching a member with its face centre on the plane) and its own pixels
  // lie about the plane's normal within max_rms_ratio (plus 1 mm) of their
  // rms about their own plane: a brick's face 30 pixels across at 2 m on an
  // active-stereo camera fits its noise to 15 degrees, and a face really
  // tilted that far does not fit the layer's plane. Degrees, [0, 45];
  // at most max_angle_deg turns this off.
  double adopt_angle_deg = 25.0;
  // ... and takes it with a looser fit (rest_max_rms_ratio) when its centre
  // lies within this share of the height its tilt would lift it to above
  // the plane: resting on the layer by one edge, so tilted, its centre
  // would sit that high; lower, part of it would lie inside the layer,
  // which the noise can put it (a brick at 2 m on an active-stereo camera,
  // its centre 2 mm off the layer's plane and its face tilted 13 degrees
  // by a blob of correlated noise that its own pixels fit 1.5 times better
  // than the layer's plane), or a gap beside the layer (a heap's carton
  // tilted 15 degrees into one: its pixels fit the layer's plane five
  // times worse). Unitless, [0, 1]; 0 always asks for max_rms_ratio.
  double rest_share = 0.5;
  // The looser fit: its pixels about the layer's plane within this times
  // (plus 1 mm) their rms about their own. Unitless, [1, 10].
  double rest_max_rms_ratio = 2.0;
  // A group beside a bigger one, its faces' centres on the bigger one's
  // plane, takes that plane when its normal is within adopt_angle_deg of
  // it and every one of its faces fits it as above: three bricks under one
  // blob of an active-stereo camera's noise at 2 m tilt together by 11
  // degrees, form a group of their own and fit a plane as wrong as theirs,
  // beside a layer of thirty whose plane is right. False: every group keeps
  // its own plane.
  bool merge_groups = true;

  absl::Status Validate() const;
};

// Turns the boxes of *boxes that share a plane with touching neighbours
// onto it (pose and grasp normal). Returns how many turned.
int AlignToLayerPlanes(const DepthImage& depth, const BoxDims& dims,
                       const LayerPlaneOptions& options, std::vector<DetectedBox>* boxes);

}  // namespace cornerpose
