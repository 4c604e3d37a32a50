// Planar patches of an organized frame: region growing over a grid of
// per-cell normals. Each cell's normal and flatness come from the points of
// a window around it (sums kept in integral images, so every window costs
// the same); a region grows from the flattest cells through neighbours whose
// normal stays within an angle of the region's and whose point lies on the
// region's plane, then takes in the points at its rim that lie on the plane
// (the windows there straddle the face's border). Touching coplanar boxes
// with no depth seam between them make one patch: the face proposals tile it.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "absl/status/status.h"
#include "common/perception/camera_model.h"

namespace cornerpose {

struct PlanarPatchOptions {
  // One cell per step_px x step_px pixels. Pixels, 1-8.
  int step_px = 4;
  // Half size of the normal window, in cells (2: 5 x 5 cells). 1-8.
  int window_cells = 2;
  // A cell is flat when its window's smallest eigenvalue is below this share
  // of the sum (windows across a depth jump or a crease are not). Unitless.
  double max_curvature = 0.05;
  // A cell joins a region when its normal is within this of the region's.
  // Degrees.
  double max_normal_angle_deg = 12.0;
  // ... and its point lies within base + per_m2 z^2 of the region's plane.
  // Metres, 1/metre.
  double plane_tolerance_base_m = 0.005;
  double plane_tolerance_per_m2 = 0.003;
  // Regions with fewer cells are dropped. Count.
  int min_cells = 12;
  // Patches within this many cells of each other whose fitted planes agree
  // (normals within merge_angle_deg, each centroid on the other's plane
  // within the tolerance above) are one patch: a face that noise broke up
  // (generated stereo frames at 1.5-2.3 m: a carton top in four pieces
  // whose fitted normals differ by 7-12 degrees). Cells (0: no merging) and
  // degrees.
  int merge_gap_cells = 2;
  double merge_angle_deg = 14.0;

  absl::Status Validate() const;
};

struct PlanarPatch {
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();   // unit, towards the camera
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();  // metres, camera frame
  double rms_m = 0.0;                                  // of the points about the plane
  std::vector<Eigen::Vector3d> points;                 // one per cell, camera frame
  bool touches_border = false;  // some cell at the image border: its outline is cut
};

struct PlanarPatches {
  std::vector<PlanarPatch> patches;
  // Per cell (row-major, cells_wide x cells_high): the patch index, or -1.
  std::vector<int> label;
  int cells_wide = 0, cells_high = 0, step_px = 1;
  // The patch at a pixel, or -1 (inline: the tiling reads it per sample).
  int PatchAt(int u, int v) const {
    const int cu = u / step_px, cv = v / step_px;
    if (u < 0 || v < 0 || cu >= cells_wide || cv >= cells_high) return -1;
    return label[static_cast<size_t>(cv) * cells_wide + cu];
  }
};

// What the patch's cells cover of a plane facing the camera at its
// centroid's depth, m^2: (z step / fx)^2 each.
double PatchCellsArea(const PlanarPatch& patch, double fx, int step_px);

// The patch's area on its plane, m^2: 1 / cos(slant) times its cells' area,
// slanted to the ray through its centroid (a carton's side at 60 degrees
// to the view is twice the area its cells count; clamped at 80 degrees).
double PatchArea(const PlanarPatch& patch, double fx, int step_px);

// With `merged_pieces` (may be null): the patches that merging
// (merge_gap_cells) joined with others, each as it was before, with a label
// map of their own (-1 outside them). Two boxes' faces on one plane with a
// shadow between them merge into a patch that is neither; their pieces
// still are. A piece holding 95 % or more of its merged patch's cells (a
// layer's top with crumbs merged into it) is left out: its outline, and so
// its faces, are the patch's.
PlanarPatches SegmentPlanarPatches(const DepthImage& depth, const PlanarPatchOptions& options,
                                   PlanarPatches* merged_pieces = nullptr);

}  // namespace cornerpose
