// Faces anchored in the corners of a planar patch that does not tile: a
// pallet layer with a box of another size in it, an L of box tops, a layer
// cut by the image border. Such an outline is no whole number of faces, so
// the tilings (face_proposals.h) propose nothing; yet each corner where two
// of its sides end in a depth jump at a right angle holds one box whose face
// fits there. The patch is rasterized on its plane, in its outline
// rectangle's axes; a face-sized rectangle is anchored where it lies on the
// patch and two adjacent sides of it run along the patch's border with
// nothing of the patch beyond (and inside the view). Both ways round, every
// face of the box that fits. The judge decides which, if any, is a box: the
// two inner sides still need a seam, a depth jump or a tiling.
#pragma once

#include <Eigen/Geometry>
#include <vector>

#include "absl/status/status.h"
#include "common/perception/camera_model.h"
#include "common/perception/planar_patches.h"
#include "common/perception/types.h"

namespace cornerpose {

struct PlaneRectangle;

struct AnchoredFaceOptions {
  // Off by default: on the 21 evaluation sets it finds two more boxes (an
  // L-shaped layer cut by the image border; a brick layer) for about 6 ms
  // a frame, the judge's time for the faces it adds. On: a cell whose
  // layers are often notched and whose corners the edges miss.
  bool enabled = false;
  // A face is on the patch when this share of its raster cells is. Unitless.
  double min_inside = 0.7;
  // Each anchored side, over its half at the anchored corner: at least
  // this share of the cells along its inner edge on the patch, at most
  // max_beyond of those just past it. Unitless.
  double min_edge = 0.7;
  double max_beyond = 0.2;
  // Patches bigger than this many of the box's largest faces are not
  // anchored in (a floor, a wall). Count.
  int max_faces = 48;
  // At most this many faces from one patch, best anchored first. Count.
  int max_per_patch = 24;

  absl::Status Validate() const;
};

// The anchored faces' box poses (the box behind the face, as TilePoses).
// `cell_m` is the patch's point spacing on its plane (metres).
std::vector<Eigen::Isometry3d> AnchoredFaces(const PlanarPatch& patch, const PlaneRectangle& rect,
                                             double cell_m, const CameraIntrinsics& camera,
                                             const BoxDims& dims,
                                             const AnchoredFaceOptions& options);

}  // namespace cornerpose
