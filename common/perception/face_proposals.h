// Face-first box hypotheses, beside the paper's corner-first ones. The frame
// is cut into planar patches (planar_patches.h); a patch whose plane and
// outline fit a face of the box (l x b, l x h or b x h), or a whole number
// of such faces side by side (a pallet layer of touching cartons), proposes
// the box-sized rectangles that tile its outline (its minimum-area
// rectangle), anchored on its sides and corners. When two tilings fit the
// outline, seam cues inside it decide (colour lines along the seams a
// tiling needs, seam_cues.h); with no cue to decide, the fewest boxes win
// (a face twice a side's width is one face, not two), and two tilings with
// as few boxes each are declined. Every proposal still goes through the
// same render-and-compare judge as the corner hypotheses.
#pragma once

#include <Eigen/Geometry>
#include <functional>
#include <optional>
#include <vector>

#include "absl/status/status.h"
#include "common/perception/anchored_faces.h"
#include "common/perception/camera_model.h"
#include "common/perception/cancel_token.h"
#include "common/perception/planar_patches.h"
#include "common/perception/seam_cues.h"
#include "common/perception/seam_split_faces.h"
#include "common/perception/types.h"

namespace cornerpose::internal {
class SharedLoops;
}  // namespace cornerpose::internal

namespace cornerpose {

struct FaceProposalOptions {
  PlanarPatchOptions patches;
  SeamCueOptions seams;
  // Faces anchored in the corners of a patch that does not tile (an L of
  // box tops, a layer with a box of another size, a layer cut by the image
  // border); anchored_faces.h.
  AnchoredFaceOptions anchored;
  // Faces split out of such a patch along the seams seen inside it (lines
  // of missing returns or grooves, parallel to its outline);
  // seam_split_faces.h.
  SeamSplitOptions seam_split;
  // The patches that merging joined with others (PlanarPatchOptions::
  // merge_gap_cells) propose their faces too, each as it was before: two
  // boxes' faces on one plane with a shadow between them merge into a patch
  // that tiles as neither. Their tilings propose poses only (no layer, no
  // declined tiling). False: the merged patches alone.
  bool propose_merged_pieces = true;
  // A run of n faces fits an outline side when it is n sizes plus 0 to
  // (n - 1) max_gap_m long, within size_tolerance_m. Metres.
  double size_tolerance_m = 0.02;
  double max_gap_m = 0.005;
  // An outline smaller than a face but at least this share of it along
  // both sides proposes the face centred on it (its rim taken in by the
  // segmentation); 0 proposes nothing from such outlines. 0.6 also found
  // a time-of-flight brick at the image's edge (0.64 of its top across),
  // but on a real stereo tabletop frame a box in the background, at the
  // image's corner, that is none (session 30). Unitless.
  double min_eroded_share = 0.65;
  // ... also when the outline tiles (one tiling): a face's top eroded by
  // the normals' window can tile as smaller faces of the box (a brick's
  // top, 0.169 x 0.058 m of 0.19 x 0.09 at 1.7 m, tiled as two of its end
  // faces), and only they were proposed. The judge decides between them.
  bool eroded_beside_tile = true;
  // A patch within a normal window of the image border whose outline is no
  // bigger than one face proposes the faces that fit it (never a layer's
  // tiles); false skips every such patch. The judge still requires a face
  // leaving the view to be measured on every side.
  bool propose_at_border = true;
  // Patches seen more obliquely than this are not proposed from. Degrees.
  double max_view_angle_deg = 65.0;
  // A patch with more tiles than this is not tiled. Count.
  int max_tiles = 64;
  // A tiling is backed by seam cues when this share of its inner tile
  // sides shows one; it wins when every other tiling's share is lower by
  // seam_support_margin (a finer tiling that shares its seams has sides
  // with none). Unitless.
  double min_seam_support = 0.5;
  double seam_support_margin = 0.25;
  // The layer check (detector.cc, CheckLayers): a layer (a patch that
  // tiles, LayerTiles) is trusted when a box ended by depth jumps on both of
  // its face's axes is one of its tiles (an outline that takes in a box of
  // another size may tile by chance; then no box found is one of its tiles);
  // on a trusted layer a box that a seam bounds must be one of its tiles
  // too. Tiles match with the centre within layer_match_m and the axes within
  // layer_match_deg (of the same sizes); a patch filling less than
  // layer_min_fill of the tiles on it is no layer. Off: no such check.
  bool check_layer_tiling = true;
  double layer_match_m = 0.04;
  double layer_match_deg = 15.0;
  double layer_min_fill = 0.7;

  absl::Status Validate() const;
};

// One way to tile a rectangular outline with equal faces of the box.
struct FaceTiling {
  int normal_axis = 2;  // box axis along the face normal
  int axis_u = 0;       // box axis along the outline's first side
  int axis_v = 1;       // box axis along its second side
  int count_u = 1, count_v = 1;
  int tiles() const { return count_u * count_v; }
};

// The tilings of a width x height outline (metres) by one face of the box,
// each distinct in face size; fewest tiles first.
std::vector<FaceTiling> TilingsOf(double width_m, double height_m, const BoxDims& dims,
                                  const FaceProposalOptions& options);

// A rectangle on a plane: centre, unit in-plane axes, extents. Metres.
struct PlaneRectangle {
  Eigen::Vector3d centre, normal, axis_u, axis_v;
  double width = 0.0, height = 0.0;  // along axis_u, axis_v
};

// The minimum-area rectangle around a patch's points, on its plane.
PlaneRectangle OutlineRectangle(const PlanarPatch& patch);

// Poses of the tiles of `tiling` over `rect` (box behind the face, its
// normal_axis face towards the camera).
std::vector<Eigen::Isometry3d> TilePoses(const PlaneRectangle& rect, const FaceTiling& tiling,
                                         const BoxDims& dims);

// The pose of one face of the box (tiling's face, its sides along rect's
// axes; counts ignored) centred at `centre` on rect's plane: the box behind
// it, as TilePoses gives a tile.
Eigen::Isometry3d FacePoseAt(const PlaneRectangle& rect, const Eigen::Vector3d& centre,
                             const FaceTiling& tiling, const BoxDims& dims);

// Share of the inner tile sides of `tiling` over `rect` that show a colour
// seam (0 without colour or inner sides).
double SeamSupport(const DepthImage& image, const PlaneRectangle& rect, const FaceTiling& tiling,
                   const BoxDims& dims, const SeamCueOptions& options);

// A patch whose outline tiles with whole faces of the box: every tile of
// every tiling still in play (the one chosen, or both of an ambiguous pair).
struct LayerTiles {
  int patch = -1;
  // The patch's area over that of the tiles on it (the least over the
  // tilings in play): about 1 for a layer, notched or not.
  double fill = 0.0;
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  std::vector<Eigen::Isometry3d> tiles;
};

struct FaceProposals {
  std::vector<Eigen::Isometry3d> poses;
  std::vector<DeclinedCandidate> declined;  // ambiguous tilings
  int num_patches = 0;
  PlanarPatches patches;
  std::vector<LayerTiles> layers;
};

// A plane whose patches propose nothing: the floor, which the detector
// finds from the patches themselves before any of them proposes. Every face
// on the floor's plane is a box reaching into it (never judged), and the
// floor's outline, cut by the image border, is the costliest patch to
// split along its seams (5-19 ms of a frame on one thread).
struct ExcludedPlane {
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  // unit
  Eigen::Vector3d point = Eigen::Vector3d::Zero();    // on the plane, camera frame
  // A patch lies on it with its centroid this close to the plane (metres)
  // and its normal within max_angle_deg of the plane's.
  double max_distance_m = 0.0;
  double max_angle_deg = 10.0;
  bool Holds(const PlanarPatch& patch) const;
};

// Given the frame's patches, the plane (if any) whose patches propose
// nothing.
using ExcludedPlaneFinder = std::function<std::optional<ExcludedPlane>(const PlanarPatches&)>;

// A stopped `cancel` (may be null) ends the tiling early, with what it has.
// With `helpers` (may be null), the patches are shared out as a loop other
// threads may help with (internal::SharedLoops); the proposals are the same.
// With `exclude`, it is called once the patches are found, and the patches
// and merged pieces on the plane it returns propose nothing (no poses, no
// layer, no declined tiling).
FaceProposals ProposeFromFaces(const DepthImage& image, const BoxDims& dims,
                               const FaceProposalOptions& options,
                               const CancelToken* cancel = nullptr,
                               internal::SharedLoops* helpers = nullptr,
                               const ExcludedPlaneFinder& exclude = {});

// The layer (an index into faces.layers) a grasp face (centre and outward
// normal, camera frame) lies on: on its patch, facing its way, on its plane,
// the patch filling layer_min_fill of its outline. -1 when none.
int LayerUnder(const FaceProposals& faces, const DepthImage& image,
               const Eigen::Vector3d& face_centre, const Eigen::Vector3d& face_normal,
               const FaceProposalOptions& options);

// Whether camera_T_box is one of the layer's tiles (centre within
// layer_match_m, axes within layer_match_deg and of the same sizes).
bool IsLayerTile(const LayerTiles& layer, const BoxDims& dims,
                 const Eigen::Isometry3d& camera_T_box, const FaceProposalOptions& options);

}  // namespace cornerpose
