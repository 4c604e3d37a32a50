// The whole detector: edge points -> edge segments -> corners -> box poses,
// each pose checked against the depth image before it is returned. A wrong
// pose is worse than a missed box (a robot acts on it), so every hypothesis
// must be confirmed by its grasp face and not contradicted anywhere.
#pragma once

#include <optional>

#include "absl/status/statusor.h"
#include "common/perception/box_evidence.h"
#include "common/perception/box_pose.h"
#include "common/perception/box_refinement.h"
#include "common/perception/cancel_token.h"
#include "common/perception/clubbing.h"
#include "common/perception/edge_pair_faces.h"
#include "common/perception/edge_points.h"
#include "common/perception/edge_segments.h"
#include "common/perception/face_proposals.h"
#include "common/perception/floor_rest.h"
#include "common/perception/layer_plane.h"
#include "common/perception/layer_turn.h"
#include "common/perception/types.h"

namespace cornerpose {

// Frames above this many points are refused: by the detector
// (DetectorOptions::max_points) and by the wire library before it unpacks
// one. Count.
inline constexpr int kMaxPoints = 20'000'000;
// An unorganized cloud is laid onto its camera's pixel grid: at most this
// many pixels (a 2048 x 2048 sensor; depth cameras are 1 MP or less, and
// stereo ones up to 2.3 MP), whatever the number of points. Count.
inline constexpr int64_t kMaxUnorganizedGridPixels = 2048 * 2048;

struct AcceptanceOptions {
  // Share of the box's unoccluded rendered pixels the depth confirms. Unitless.
  double min_support = 0.6;
  // Share of the grasp face's unoccluded pixels the depth confirms. Unitless.
  double min_grasp_support = 0.8;
  // Share of the grasp face that may be hidden by something in front. Unitless.
  double max_grasp_occluded = 0.25;
  // Largest share of the box's rendered pixels hidden by something in front
  // of it (a box pushed through the floor or a neighbour hides most of
  // itself; a real box in a heap under others up to a third). Unitless.
  double max_occluded = 0.4;
  // Largest share of rendered pixels seen through the box (free space or
  // points inside its volume where the box would be). Unitless.
  double max_see_through = 0.05;
  // Grasp face pixels needed (at the sampling the evidence uses). Count.
  int min_grasp_pixels = 60;
  // A face measured between two free sides must match its known size within
  // this. Metres.
  double extent_tolerance_m = 0.025;
  // ... and a face so measured on both axes that is short of the box on
  // both by more than this is a box of another size (a smaller box whose
  // top lies within extent_tolerance_m of this box's face each way, read
  // as this one on end). Cartons bulge more than they shrink, and edge
  // bands make a face read long: over the 78 evaluation sets no box found
  // right was more than 6 mm short on both axes. With
  // DetectorOptions::size_tolerance_m set, that tolerance. Metres; 0: off.
  double max_short_both_axes_m = 0.012;
  // A side of the grasp face with nothing seen near it (kUnknown: a shadow's
  // missing returns) may hide more face, as an occluded side does: the box
  // is declined when a longer side of the box could stand in there (a
  // carton lying flat, its top's far end in the shadow of a box standing
  // over it, read as a carton on its side). False: an unseen side says
  // nothing.
  bool check_unseen_sides = true;
  // With two sides of the grasp face across each other hidden, the face
  // turned a quarter (longer where it was shorter) could stand there too:
  // true leaves that reading to DetectorOptions::turned_check, which
  // judges it at the corner between the two measured sides and takes the
  // box out when it is a box too; false declines every such box ("a
  // hidden side could be a longer side of the box"), as before session 30.
  // Off whenever turned_check is off.
  bool turned_hidden_corner_to_check = true;
  // ... unless the depth image rules that longer reading out: at least this
  // share of the box so read (internal::LongerUnderSide) is seen
  // through, the camera seeing the floor past the shadow where the box
  // would be (a brick in a heap, its ends in its own shadows). Four times
  // what a box kept may show (max_see_through). Occluded sides keep the
  // rule: what stands over one hides where the face goes on. Unitless,
  // [0, 1]; 0: an unseen side always leaves the size in doubt.
  double unseen_longer_see_through = 0.2;
  // Largest angle between the grasp face's normal and the line of sight to
  // its centre. Degrees.
  double max_grasp_view_angle_deg = 60.0;
  // The grasp face must project this far inside the image. Pixels.
  double border_margin_px = 3.0;
  // ... unless every side of it was found where the face ends (free or a
  // seam, with a free side on leaving_view_free_axes of its two axes): then
  // a corner out of view hides nothing about where the box is. False: every
  // face in view, whole.
  bool measured_face_may_leave_view = true;
  // A face no more than this share of which lies past the border (sampled
  // on a 10 x 10 grid, border_margin_px in) is judged as in view, when the
  // refinement read each of its sides (none unknown): a corner just past
  // the border hides no more of its size than a side occluded does. A stereo
  // heap's carton whose corner reached 6 px past the image's bottom, three
  // sides free and one under a box in front, was declined. 0: every corner
  // in view. Unitless, [0, 1).
  double max_out_of_view_share = 0.1;
  // 1: one free side anywhere (a seam's turn is measured since the
  // fourteenth round); 2: a free side on each axis (the rule before session
  // 17); 0: seams on all four suffice. Count, [0, 2].
  int leaving_view_free_axes = 1;
  // A face the image border cuts across one axis is returned when its
  // other three sides were measured (free or a seam) and it is seen on its
  // plane from its measured end to the border for longer than any shorter
  // side of the box that could stand there, over at least
  // min_in_view_share of its length (internal/border_faces.h): the known
  // size and the measured end say where it ends out of view. The cartons at
  // the edge of a view a pallet layer fills. False: such faces are
  // declined ("grasp face cut by the image border").
  bool face_may_run_out_of_view = true;
  // Share of the cut side's length that must be in view. Unitless, (0, 1].
  double min_in_view_share = 0.6;
  // ... the view ending, for that test, where a run of pixels with no
  // return reaches the border: the band along one side of an active
  // stereo camera's image where it returns nothing. The face must still be
  // seen, on its plane, past every shorter side that could stand there.
  // False: those pixels count as not on the face.
  bool border_band_ends_view = true;
  // A side the refinement finds running on flat (no seam in depth or
  // colour) is a seam where it lies against the grasp face of a box already
  // kept, coplanar and aligned with it (internal/kept_neighbours.h): in a
  // layer of touching boxes the kept box vouches for a seam the sensor does
  // not show. The box must still be ended on its other sides. False: such a
  // side declines the box ("a side runs on flat").
  bool kept_box_ends_side = true;
  // Two hypotheses declined only for one side running on flat, every other
  // side ended, whose flat sides lie against each other's grasp face
  // (coplanar and aligned, as kept_box_ends_side asks) end each other: both
  // are judged again, each with the other taken as kept, and returned when
  // both pass. Two touching boxes whose shared seam shows nothing, every
  // other side of both ended. False: both declined.
  bool pairs_end_each_other = true;
  // Two accepted boxes may not overlap by more than this (each is shrunk by
  // it before the overlap test). Metres.
  double overlap_margin_m = 0.015;
  // A hypothesis whose box, shrunk by this on every side, overlaps a box
  // already kept is not judged while that box is kept: refinement moves a
  // pose by at most RefinementOptions::max_shift_m (5 cm) and turns it by
  // at most max_turn_deg, so at 5 cm it would still overlap the kept box by
  // more than overlap_margin_m afterwards and be dropped. On pallets that is
  // a quarter of all refinements (neighbours of neighbours, second starts,
  // turned readings, each on a box found). It may be proposed again later
  // (a box a check takes out frees its place). 0: every hypothesis is
  // judged. Metres.
  double settled_overlap_margin_m = 0.05;
  // ... nor while a hypothesis judged before it in the same batch (in the
  // order proposed) is accepted there with a free border on all four sides
  // of its face: a box's corners, face tiles and neighbours propose it,
  // and other readings of its place, several times over, and after such a
  // reading the rest could only be dropped (the most free sides are kept
  // first) or, with four free sides and a higher score, kept in its place
  // (measured: the same boxes on every evaluation set, poses within 2 mm).
  // Refinements on the clutter set -9 %. False: every hypothesis of a batch
  // is judged and the best-ranked kept. (Settling behind any accepted
  // reading cut 30 % but kept a wrong reading of a nearly square carton
  // over the right one the ranking would have chosen.)
  bool settle_within_batch = true;

  absl::Status Validate() const;
};

struct DetectorOptions {
  BoxDims box;  // required: the known size of the boxes, metres
  EdgePointOptions edge_points;
  EdgeSegmentOptions segments;
  ClubbingOptions clubbing;
  PoseOptions pose;
  RefinementOptions refinement;
  EvidenceOptions evidence;
  AcceptanceOptions acceptance;
  // The camera of an unorganized cloud, used to render hypotheses; organized
  // clouds carry their own (recovered from the points). Default: Kinect VGA.
  std::optional<CameraIntrinsics> camera;
  // Face-first hypotheses from planar patches (face_proposals.h), judged
  // with the corner ones. False gives the corner-only detector.
  bool face_proposals = true;
  FaceProposalOptions faces;
  // Faces between two parallel edge segments a side of the box apart
  // (edge_pair_faces.h), judged with the face tiles: a box in a heap whose
  // long sides show as edges and whose corners do not.
  EdgePairOptions edge_pairs;
  // A frame in which nothing is found has its planar patches found once
  // more with the normal window this wide (cells; PlanarPatchOptions::
  // window_cells), unless the caller set that window, and its hypotheses
  // judged again (its edge points, segments and corners stand): a pallet
  // at 2-2.5 m from a stereo camera (~1 cm of noise) comes out of the 5 x 5
  // and 7 x 7 windows in pieces too small to propose a face. 0: never.
  int empty_frame_window_cells = 4;
  // With face proposals: no box reaches more than floor_tolerance_m through
  // the floor, the farthest plane the camera sees with planar patches of at
  // least floor_min_area_m2 (and three of the box's largest faces) on it
  // (detector.cc, FindFloor). The floor is found before the hypotheses are
  // judged, and one through it is declined then, so that it cannot outrank
  // another reading of the same face. Metres, square metres.
  bool floor_check = true;
  // Returned boxes side by side on one plane (a pallet layer) take the
  // plane fitted through all their faces (layer_plane.h; max_angle_deg 0
  // turns it off).
  LayerPlaneOptions layer_plane;
  // ... and, where a box touches min_agreeing others on its plane that
  // agree on their in-plane turn, the layer's turn (layer_turn.h;
  // min_agreeing 0 turns it off).
  LayerTurnOptions layer_turn;
  // Then a box resting on the floor (floor_check's floor), its bottom
  // tilted into it by a face fit's error, lies flat on it (floor_rest.h;
  // `floor_rest.max_tilt_deg` 0 turns it off).
  FloorRestOptions floor_rest;
  double floor_tolerance_m = 0.03;
  // False: a face proposal lying on the floor found (every corner of its
  // box at most 1.5 cm above the floor's plane, the deepest more than
  // floor_tolerance_m + 2 cm beyond it) is not judged: refinement fits its
  // face to the floor, so it would be declined as reaching into the floor
  // (a noisy stereo floor's seam lines framed hundreds of faces a frame,
  // a tenth of the pose stage; the same boxes on every evaluation set).
  // The planar patches on the floor's plane (centroid within the floor's
  // tolerance or half the box's thinnest side, normal within 10 degrees)
  // then propose nothing at all: the floor is found from the patches first
  // (splitting its border-cut outline along seams was most of the faces
  // stage). True judges them as every other proposal.
  bool judge_faces_on_floor = false;
  double floor_min_area_m2 = 0.25;
  // ... and it is the floor only when at most this share of the frame lies
  // beyond it (a lower layer's top or a pallet deck is the farthest plane
  // found while the floor itself shows past it). 0.01 until session 28: a
  // noisy stereo floor at 2.4 m (1 cm scatter) had 1.1 % of its own
  // returns beyond it, no floor was found, and a face on bare floor was
  // returned. Unitless, [0, 1].
  double floor_max_beyond_share = 0.02;
  // With face proposals: a box whose top lies level (within this) with two
  // or more boxes found beside it (grasp faces parallel and touching, as
  // far as the box's largest face would reach: a layer around it) but
  // whose bottom would lie more than this below
  // theirs is taken out: it would stand in a hole in what they stand on.
  // What it is: a box of another size whose top matches one of the box's
  // faces (a smaller box in a layer of flat cartons read as a carton on
  // end). 0 turns the check off. Metres.
  double max_below_neighbours_m = 0.05;
  // ... and one such box that a side of it lies against (touching, its
  // sides aligned: internal::SideAgainstKeptBox) is a layer on its own:
  // boxes in a heap do not meet flush along a whole side. The carton_flat
  // (0.30 x 0.20 x 0.10 m) lying flat with a tape edge halfway across its
  // top reads as one on its side beside its single neighbour. False: two
  // neighbours always.
  bool flush_neighbour_is_layer = true;
  // A box with a side its refinement did not measure (tiled, running on,
  // hidden) is taken out when its grasp face turned a quarter about its
  // normal, at one of its corners between two measured sides (free or a
  // seam), is judged a box too: two readings of one face that the evidence
  // cannot separate (a tape edge taken for a seam makes a carton turned
  // across two). Faces whose sides differ by less than 2 cm are skipped.
  bool turned_check = true;
  // A hypothesis from a corner that the first look turns away or that
  // refinement moves too far is judged once more with its face turned onto
  // the plane the depth image shows in the face's middle, when the two
  // differ by 2-30 degrees (internal::TiltOntoDepth): the corner's segments
  // set its normal, and an active stereo camera's depth noise along them
  // tilts it by 15-20 degrees, more than refinement may turn it.
  bool corner_tilt_onto_depth = true;
  // A box whose face is bounded by seams on both sides of one axis, with
  // fewer than two free sides, is taken out when its face shifted half its
  // width along that axis is judged a box with more free sides: the seams
  // were lines inside two faces (the tape along the middle of two cartons'
  // flaps frames a carton straddling them), and the shifted reading, ended
  // by the layer's edge, is the box. The retaken readings then get their
  // turn (retake_outranked).
  bool shifted_check = true;
  // Two boxes read side by side on one face, their faces together another
  // face of the box (internal::OneBoxForPair: a carton whose height is half
  // its width has a top that its flap seam splits into two faces the size
  // of its side), are both taken out when that one box is judged a box too:
  // a stereo pallet of such cartons gave pairs of cartons on their side,
  // the best box of its frame among them. The one box's reading then gets
  // its turn (retake_outranked).
  bool paired_check = true;
  // A hypothesis the judge accepted that a box kept before it overlapped
  // (it ranked below it) is judged again, and kept when it passes, once a
  // plausibility check (layer, level, gaps, turned readings) has
  // taken that box out: the reading that won is gone, the one it outranked
  // may be the box. False: it stays lost.
  bool retake_outranked = true;
  // A hypothesis refined and declined for a side that runs on flat proposes
  // its face turned a quarter about its normal at each of its corners
  // between two measured sides (free or a seam): a corner proposes both
  // readings of its box, and the one turned the wrong way runs on past the
  // true box's shorter side. Only faces whose sides are both at least
  // refinement.seam_turn_min_length_m long (a shorter side cannot measure
  // the face's turn: turned bricks came out 13 degrees off) and differ by
  // 2 cm or more. A turned reading declined in turn proposes none (its
  // other corners' readings cost a third more refinements for little).
  // Off since session 36: on the 94 generated sets, side by side in one
  // run, off finds 15 boxes more (Kinect pallets +11, stereo pallets
  // without colour +5) and returns one wrong box fewer; on the benchmark's
  // clutter set one box fewer (104 of 115), refinements 682 -> 612.
  bool turned_proposals = false;
  // How far a real box may be off its nominal size (bulge, sag, crushed
  // corners) and still be the box. Unset keeps each stage's own tolerance
  // (pose.length_tolerance_m 0.025, acceptance.extent_tolerance_m 0.025,
  // refinement.tile_tolerance_m 0.01, faces.size_tolerance_m 0.02). Set,
  // it gives: faces.size_tolerance_m = T, refinement.tile_tolerance_m =
  // 2/3 T, and pose.length_tolerance_m = acceptance.extent_tolerance_m =
  // T + 0.01 (what the edge bands and the depth noise add). Metres, (0, 0.1].
  std::optional<double> size_tolerance_m;
  // Parameters from geometry: edge_points.radius_m, segments.ransac_threshold_m
  // and clubbing.meet_distance_m left at their defaults (0.02, 0.01, 0.01)
  // follow the box size and the frame's median depth z (see
  // DeriveGeometryParameters); a value the caller changed is kept. False
  // keeps the defaults as they are.
  bool parameters_from_geometry = true;
  // The resolution the edge stage works at (EdgePointOptions::lattice_px):
  // every k-th pixel, k = floor(r_s fx / z / edge_lattice_radius_px) at the
  // frame's median depth z, so r_s spans at least this many lattice steps;
  // 1 when it spans fewer. The edge score of each pixel still reads its
  // whole neighbourhood at full resolution, and the boxes are refined and
  // judged on every pixel. 0 keeps edge_points.lattice_px as it is. Pixels.
  double edge_lattice_radius_px = 5.0;
  // A returned box's score is the judge's (its faces' support) times the
  // share of its outline in the image (internal::BoxViewShare): a box
  // partly out of view ranks below one wholly in view that the depth
  // supports as well. What lies out of view cannot be checked for what
  // touches the box, and a grasp planned on it is a guess. Which boxes are
  // returned does not change. False reports the judge's score.
  bool score_in_view = true;
  // Declined hypotheses reported per frame (the strongest). Count, >= 0.
  int max_declined = 8;
  // A hypothesis refined and declined may be proposed once more from
  // another start (a face tile after a corner, a neighbour of a box found
  // later) and is then judged again: where refinement reads a side depends
  // a little on where it starts. False: every pose is judged once.
  bool retry_declined = true;
  // Each confirmed box proposes the boxes that would touch it side by side
  // (pallet layers, where seams leave few edges), neighbour_gap_m apart.
  bool propagate_to_neighbours = true;
  double neighbour_gap_m = 0.002;
  // ... and the boxes beside it a layer down (one box height below, in its
  // orientation): on a pallet stacked at two heights, the lower layer's
  // boxes next to an upper one (their patches often in pieces at a stereo
  // camera's range, their corners against the upper box's wall).
  bool neighbours_a_layer_down = true;
  // A neighbour so proposed that is declined only because a side of its
  // face runs on flat (the seam there not seen), with a seam on another
  // side, still proposes its own neighbours, and so on, up to this many declined boxes in a row
  // past the last box accepted: in a pallet layer whose fine seams show on some boxes' sides and
  // not on others', the chain from a box found would stop at the first seam missed, though the
  // boxes beyond it show theirs. A declined box is never returned; what it proposes is judged like
  // any hypothesis and, once accepted, refined again from its refined pose, where it must pass the
  // refinement's part of the test once more (a brick's length across the seam between two bricks,
  // accepted from a lucky start, moves off there and finds a side running on flat); so must the
  // neighbours of a box so reached, and theirs. Count, [0, 4]; 0: the chain stops at the first
  // box declined.
  int neighbour_steps_past_declined = 2;
  // Unorganized clouds are projected through `camera` onto its pixel grid
  // (the nearest point per pixel) and processed like a frame. Right for a
  // cloud from one depth camera, in its frame; for merged or foreign clouds
  // set it false to score edges over a k-d tree as the paper does (also
  // done when fewer than half the points project into the image).
  bool project_unorganized = true;
  // Worker threads (edge points). Count.
  int num_threads = 2;
  // Frames above this many points are refused. Count.
  int max_points = kMaxPoints;

  absl::Status Validate() const;
};

// Sets the edge radius r_s and the gap at which a segment ends, which
// Algorithm 1 ties to it: every front end sets r_s through this.
void SetEdgeRadius(double radius_m, DetectorOptions* options);

// The camera of a frame whose source knows it (a depth image, a device)
// replaces the one in *options (a request's intrinsics, the default); a
// frame without one leaves *options unchanged.
void UseFrameCamera(const std::optional<CameraIntrinsics>& frame_camera, DetectorOptions* options);

// The geometry rule, applied to the fields left at their defaults: r_s =
// min(0.35 x the box's smallest side, max(0.02 m, 6 pixels at depth z));
// RANSAC threshold and meeting distance r_s / 2; the segment gap r_s. So a
// 3 cm edge at 0.6 m gets r_s = 1.05 cm; a carton at 1-2.5 m keeps 2 cm.
// The planar patches' normal window grows from 5 x 5 to 7 x 7 cells where
// 7 cells span at most 0.8 of the smallest side at z (cartons, not bricks).
// `focal_px` is the camera's fx; z in metres (<= 0: unknown, depth term off).
void DeriveGeometryParameters(double median_depth_m, double focal_px, DetectorOptions* options);

// Runs the detector on one cloud. Empty, all-NaN and box-free clouds give an
// empty Detection; malformed clouds and bad options give INVALID_ARGUMENT.
// When `cancel` stops (its deadline passes or its caller goes away) the
// detection ends within a few milliseconds with DEADLINE_EXCEEDED or
// CANCELLED: it is checked between the stages and inside their long loops.
// A frame with edge points in which nothing is found has its faces found
// and judged once more with a wider normal window (DetectorOptions::
// empty_frame_window_cells); its faces and poses timings then count both.
absl::StatusOr<Detection> DetectBoxes(const PointCloud& cloud, const DetectorOptions& options,
                                      const CancelToken& cancel = CancelToken());

}  // namespace cornerpose
