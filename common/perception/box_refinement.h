// Pose refinement on the grasp face: corners come from the blurred edge
// bands and are good to a centimetre or so; the face the camera looks at has
// hundreds of points. The face's plane fixes its normal and depth, and each
// free side of it (where the face ends in a depth jump, not in a coplanar
// neighbour) fixes the face's position and turn in its own plane.
#pragma once

#include <array>
#include <cstdint>
#include <optional>

#include "absl/status/status.h"
#include "common/perception/camera_model.h"
#include "common/perception/seam_cues.h"
#include "common/perception/types.h"

namespace cornerpose {

struct RefinementOptions {
  // Points within this distance of the face's plane belong to it. Metres.
  double plane_tolerance_m = 0.015;
  // Band outside a side searched for a coplanar continuation, and the
  // margin kept clear of corners when measuring a side. Metres.
  double side_band_m = 0.02;
  // A side is free when its outer band holds fewer coplanar points than this
  // share of its inner band. Unitless.
  double free_side_ratio = 0.15;
  // Least depth of the groove between two touching coplanar faces. Metres.
  // A seam is a groove at least this deep (metres) or a line where the
  // share of pixels that see the plane falls below this share of its
  // flanks'.
  // Fine seams (gaps under ~1 mm) can show neither; the side then counts as
  // continuing and the box is not returned rather than guessed.
  double min_seam_depth_m = 0.0015;
  double max_seam_density = 0.75;
  // A density dip down to this share also makes a seam when a groove of
  // half min_seam_depth_m comes with it.
  double weak_seam_density = 0.85;
  // A groove alone (no dip in density with it) must also be deeper than
  // this many times the face's own roughness (the RMS of its interior about
  // the fitted plane): a Kinect's disparity steps lay stripes a step high
  // (5-6 mm at 1.4 m) across a flat deck board, and one running along a
  // side read as a 1.6 mm groove (a brick-sized piece of a board beside a
  // layer, returned as a brick). 0: min_seam_depth_m alone. Unitless,
  // [0, 10].
  double seam_depth_per_rms = 1.0;
  // A gap finer than a pixel leaves a sparse line of missing returns rather
  // than a gap in the points: it is a seam when the share of pixels along
  // it that return nothing on the plane exceeds its flanks' share by at
  // least sparse_seam_missing and the excess is at least sparse_seam_sigma
  // standard deviations of the flanks' rate (Poisson). Measured on the
  // synthetic Kinect pallets: lines inside faces reach an excess of 0.04 at
  // most, seams 0.06-0.5. 0 for either disables the test. Unitless.
  double sparse_seam_missing = 0.05;
  double sparse_seam_sigma = 3.0;
  // The groove is looked for this far either side of the hypothesised side.
  // Metres.
  double seam_search_m = 0.006;
  // ... and this much further outward: a face placed by its free side, which
  // reads long by a fattened edge or a bulge, puts the seam side short of
  // the seam. A seam found only there counts when no side of the face is
  // hidden or cut. Metres.
  double seam_search_outward_m = 0.004;
  // A seam must show in each half of the side too, with at least this
  // strength (how far past its thresholds; 0 = at them, negative = short of
  // them by that share): random clusters of missing returns make a dip in
  // one place. -1 or less: no such check.
  double seam_halves_min_strength = 0.0;
  // A face that runs on past a side is one tile of a layer when the layer
  // ends a whole number of (box size + tile_gap_m) away, within
  // tile_tolerance_m, searched up to max_tile_march_m (0 disables). Metres.
  double tile_gap_m = 0.002;
  double tile_tolerance_m = 0.01;
  double max_tile_march_m = 2.5;
  // The layer rule above applies only to a face with a seam (in depth or
  // colour) on at least one of its other sides: a flat plane of the right
  // size with no seam anywhere (a laptop lid, a table top, a wall) tiles as
  // well as a layer of touching boxes, and nothing in the frame tells them
  // apart (precision first). True applies it to every face (a cell that
  // sees only pallet layers of known boxes).
  bool tile_uncued_sides = false;
  // With a registered colour image: a side where the face runs on is a seam
  // when a straight image line runs along all of it (seam_cues.h).
  SeamCueOptions colour_seams;
  // With a registered colour image: a groove in the depth is a seam only if
  // at least this share of the side shows an image line along it too (a
  // stereo camera's noise leaves grooves inside a face; two boxes that
  // touch leave a line in the image). 0 trusts the depth alone. Unitless.
  double colour_confirms_seam = 0.5;
  // A side where the face runs on but ends within side_band_m (nothing on
  // its plane a band further out) is free where the face ends, when it is
  // the face's only such side, its opposite side is free and no side is
  // hidden or cut: a carton's bulge, or an active stereo camera's fattened
  // edges and smoothing (a brick at 1.4 m seen a centimetre long at one
  // end). The measured extent is still checked against the box's size.
  bool rim_ends_side = true;
  // ... and when the face so measured is the box's size: across the rim
  // from this short to twice this long, along it within this (where both
  // its sides are free). Metres.
  double rim_extent_tolerance_m = 0.015;
  // ... and also when its opposite side is occluded instead of free (a box
  // standing in front there, under which the face may go on), the face's
  // other two sides measured (free or a seam), and no side hidden or cut:
  // in a heap seen by an active stereo camera the fattened edge of a top
  // whose other long side a box in front hides left the top unmeasured
  // across. The face's extent across the rim is then the box's, from the
  // rim.
  bool rim_beside_occluded = true;
  // A side past which the face's plane goes on along only part of it is
  // free when, read in 1 cm stretches, the face ends within 5 mm past the
  // side along at least this share of it: what lies flat past the rest is
  // something else touching the box there (in a heap, a neighbour's face
  // crossing the plane at one corner; a box beside it set off by most of a
  // side). The side is then where the face ends along those stretches.
  // A face that runs on (a bigger face, a layer) does so along all of the
  // side. 0.67 until session 28; 0.55 found 12 more heap boxes over the
  // 78 evaluation sets, and no wrong one once DetectorOptions::
  // shifted_check took out a carton straddling two and the floor of a
  // noisy stereo frame was found (floor_max_beyond_share): a face on that
  // bare floor ended along 0.55 of its sides. 0.35 since session 29, with
  // side_ends_alone_share: 13 more boxes on 46 sets (two cartons side by
  // side, their level tops offset along the side they share), no wrong one.
  // 0: off (the side runs on, or is a seam). Unitless.
  double side_ends_share = 0.35;
  // A side so found free along less than this share of it is free only
  // when at least two of the face's three other sides are measured (free
  // or a seam): a face across two bricks lying in an L with level tops,
  // turned a quarter, ends along part of a side as well, with two sides
  // hidden (0.25 without this rule: a wrong brick). Unitless, [0, 1].
  double side_ends_alone_share = 0.55;
  // A seam found along a side whose stretch (its length less a band at
  // each end) is at least this long turns the face as a free side does:
  // by where each half of the side has the seam. Seams along shorter
  // sides give a position only (a millimetre over a few centimetres is
  // degrees). 0: seams never turn the face. Metres.
  double seam_turn_min_length_m = 0.1;
  // ... by at most this much per iteration: a seam's two halves lie a few
  // centimetres apart and their offsets are noisy (a larger turn is made
  // over the iterations, and a neighbour starts from its proposer's turn).
  // Degrees.
  double seam_turn_max_deg = 2.0;
  // Iterations of measure-and-update. Count.
  int iterations = 2;
  // One iteration more when the last one still turned the face so far that
  // its corners moved more than this: a hypothesis that started a few
  // degrees off is still turning, and the ends of its long sides, where a
  // seam is looked for within seam_search_m, are read that far off (a
  // carton_l corner 4.8 degrees off ended 2 degrees off after two
  // iterations, its sides read as running on). 0: never. Metres.
  double extra_step_corner_move_m = 0.003;
  // A hypothesis whose first iteration finds a side running on flat and no
  // seam on any side, having moved it less than this, ends there: the next
  // iteration would read the same bands, and it is declined for that side
  // (RefineOnGraspFace then returns ok with the first iteration's sides and
  // pose). 0 runs every iteration. Metres.
  double end_on_flat_shift_m = 0.003;
  // On a face with two opposite free sides, where the face's plane goes on
  // past a gap of slat_gap_min_m to slat_gap_max_m beyond each (on two of
  // three lines across the side): RefinementResult::past_gap. A face so
  // between two gaps in one flat surface, with no box found beyond either,
  // is a board of a pallet's deck or a slat, not a box (DetectorOptions::
  // gaps_check). slat_gap_max_m 0 turns it off. Metres.
  double slat_gap_min_m = 0.015;
  double slat_gap_max_m = 0.06;
  // A side with no point on the plane just inside it (kUnknown: hidden,
  // or a shadow's missing returns) where at least this share of the pixels
  // there (10 or more) see behind the plane is seen through
  // (RefinementResult::seen_through): the face ends before it, and a face
  // that big is not there (a carton lying on its 0.25 x 0.20 side read as
  // its 0.25 x 0.25 end). 0 turns it off. Unitless, [0, 1].
  double seen_through_share = 0.4;
  // Largest correction accepted, beyond which the hypothesis is not this
  // box: metres and degrees.
  double max_shift_m = 0.05;
  double max_turn_deg = 12.0;
  // A reading whose first step already moved it more than this times
  // max_shift_m, or turned it more than this times max_turn_deg, ends there
  // (moved too far) without the steps after it: of 9 054 refinements on
  // five evaluation sets (every sensor, heaps and pallets), none that far
  // after its first step came back within the limits, and such readings
  // took a ninth of all refinement steps. Unitless, >= 1; 0: every step.
  double first_step_give_up_factor = 2.0;

  absl::Status Validate() const;
};

// What lies beyond one side of the grasp face.
enum class SideKind : uint8_t {
  kUnknown,    // too few points near the side (hidden or out of view)
  kFree,       // the face ends: a depth jump, a crease or no return
  kSeam,       // a coplanar face continues past a groove: a touching box
  kOccluded,   // something lies in front just past the side: the face may go on
  kTiled,      // the face goes on, flat, and ends a whole number of boxes away
  kContinues,  // the face goes on, flat: the box is not this size here
};

struct RefinementResult {
  std::array<SideKind, 4> sides{};  // +a, -a, +b, -b of the grasp face
  bool ok = false;
  int free_sides = 0;   // of the grasp face's four
  int face_points = 0;  // points on the grasp face
  int steps = 0;        // refinement steps taken
  double plane_rms_m = 0.0;
  // Measured extent of the face between two free sides along its two axes,
  // or 0 where a side is not free. Metres.
  double extent_a_m = 0.0;
  double extent_b_m = 0.0;
  // Per side (+a, -a, +b, -b), on faces with two opposite free sides: the
  // point (camera frame) where the face's plane goes on past a gap beyond
  // the side (RefinementOptions::slat_gap_min_m), if it does.
  std::array<std::optional<Eigen::Vector3d>, 4> past_gap;
  // Per side, kUnknown ones only: the pixels just inside it see behind the
  // face's plane (RefinementOptions::seen_through_share): the face does not
  // reach the side.
  std::array<bool, 4> seen_through{};
};

// Refines camera_T_box in place using the face `grasp_face`.
RefinementResult RefineOnGraspFace(const DepthImage& depth, const BoxDims& dims, BoxFace grasp_face,
                                   const RefinementOptions& options,
                                   Eigen::Isometry3d* camera_T_box);

}  // namespace cornerpose
