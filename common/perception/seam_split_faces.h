// Faces split out of a planar patch along the seams seen inside it. A layer
// of touching boxes cut by the image border (or notched, or with a box of
// another size in it) is no whole number of faces and shows no corner where
// two of its sides end in a depth jump, so neither the tilings nor the
// anchored faces propose from it; yet on a structured-light camera the
// seams between its boxes are plain: straight lines of missing returns (or
// a groove) across the patch. Lines parallel to the patch's outline
// rectangle are scanned across it; those where many more samples have no
// return, or lie behind the plane, than on the rest of the patch are seams.
// The seams and the outline's sides in view are the places a face may end:
// every pair of them a side of the box apart on one axis, with a pair a
// side apart on the other, frames a face of the box, which is proposed. The
// judge decides, as for every proposal (each side still needs its seam or
// depth jump there).
#pragma once

#include <Eigen/Geometry>
#include <vector>

#include "absl/status/status.h"
#include "common/perception/camera_model.h"
#include "common/perception/planar_patches.h"
#include "common/perception/types.h"

namespace cornerpose {

struct PlaneRectangle;

struct SeamSplitOptions {
  // False proposes nothing.
  bool enabled = true;
  // Lines are scanned this far apart, and sampled this densely along.
  // Metres, (0, 0.02].
  double step_m = 0.002;
  // A line is a seam when at least this share of its samples on the patch
  // has no return or lies behind the patch's plane... Unitless, (0, 1].
  double min_seam_share = 0.15;
  // ... and that share is at least this many times the median line's of
  // the patch (speckle holes). Unitless, >= 1.
  double min_seam_ratio = 3.0;
  // Two places a face may end frame it when they are a side of the box
  // apart within this. Metres, (0, 0.05].
  double size_tolerance_m = 0.015;
  // Patches whose outline has a side longer than this are not scanned: a
  // floor or a wall (a floor's scan cost 13 ms). A pallet's layer reaches
  // 1.6 m (4 cartons of 0.4 m: the dev set's generator lays such grids),
  // and its outline a little more. Metres, (0, 100].
  double max_side_m = 2.0;
  // On a patch the image border cuts, the lines run along the outline
  // rectangle turned in its plane by up to align_max_deg (in steps of four
  // align_step_deg, then of one around the best) to where the patch's holes
  // and the grey image's thin dark lines line up best: the outline of a
  // layer cut by the border may be the border's, far off the seams. 0:
  // along the outline.
  // Degrees, [0, 45] and (0, 10].
  double align_max_deg = 45.0;
  double align_step_deg = 0.5;
  // With a registered grey image, a line is a seam too when at least this
  // share of its samples on the patch is darker, by colour_min_contrast
  // grey levels, than the image colour_flank_m to either side of the line:
  // a seam the depth does not show (active stereo fills it) is a dark line
  // along the whole layer; the edges of tape, labels and print are darker
  // on one side only, or along part of a line. 0: depth seams only.
  // Unitless [0, 1], metres (0, 0.05], grey levels (0, 255].
  double colour_seam_share = 0.5;
  double colour_flank_m = 0.01;
  double colour_min_contrast = 4.0;
  // At most this many faces from one patch. Count, [1, 1000].
  int max_per_patch = 32;

  absl::Status Validate() const;
};

// The split faces' box poses (the box behind the face). `patch_id` indexes
// `patches`; `rect` is its outline rectangle (OutlineRectangle).
std::vector<Eigen::Isometry3d> SeamSplitFaces(const DepthImage& depth, const PlanarPatches& patches,
                                              int patch_id, const PlaneRectangle& rect,
                                              const BoxDims& dims, const SeamSplitOptions& options);

}  // namespace cornerpose
