// Stage 4: a box pose from two perpendicular edges that meet at a corner
// (seed paper section 4, eqs. 4-5 and Table 1).
//
// p1 is the corner, d1 and d2 the unit directions of the two edges away from
// it, t = -p1/|p1| the direction to the camera. The measured edge lengths are
// matched to the known sides l, b, h; the remaining side's axis is the one
// that points to the camera (d . t > 0 with d = d1 x d2, flipped if not), and
// the signs of the two edge axes follow so that the frame is right-handed.
#pragma once

#include <vector>

#include "absl/status/statusor.h"
#include "common/perception/types.h"

namespace cornerpose {

struct PoseOptions {
  // An edge matches a side when |length - side| is below this. Metres.
  double length_tolerance_m = 0.025;
  // An edge shorter than a side by more than the tolerance may still be that
  // side, partly hidden, when it is at least this fraction of it. Unitless.
  double min_occluded_fraction = 0.3;
  // An edge longer than a side may be that side followed by the same edge of
  // a touching box ("runs on"); allowed when true.
  bool allow_run_on = true;
  // Further corners of the box refine the pose when they fall within this
  // distance of a predicted corner. Metres.
  double corner_match_m = 0.03;
  // A corner proposes at most this many of the readings its two edges
  // allow, the cheapest (MatchEdgeLengths' order; one tying with the last
  // is kept too); 0: all of them, up to six. The others read an edge as
  // hidden or running on where a cheaper reading fits it: on the 94
  // generated sets a third of all refinements, and at most 3 (session 36)
  // lost 3 of 5 914 boxes and 2 of 18 wrong ones (at most 2: 15 boxes).
  // Count, >= 0.
  int max_readings_per_corner = 3;

  absl::Status Validate() const;
};

// How the two measured edges map onto the box's axes.
struct AxisAssignment {
  int axis1 = 0;  // box axis (0 = x/l, 1 = y/b, 2 = z/h) along d1
  int axis2 = 1;  // box axis along d2
  // 0 for an exact length match of both edges, growing with the mismatch.
  double length_cost = 0.0;
};

// The assignments of (axis1, axis2) the two edge lengths allow, cheapest first.
std::vector<AxisAssignment> MatchEdgeLengths(double length1, double length2, const BoxDims& dims,
                                             const PoseOptions& options);

// The first `max_readings` of MatchEdgeLengths' list (cheapest first), and
// any that cost as much as the last of them; all when max_readings <= 0.
std::vector<AxisAssignment> CheapestReadings(std::vector<AxisAssignment> readings,
                                             int max_readings);

// camera_T_box from a corner p1 and the directions d1, d2 of its two edges
// (camera frame; need not be exactly perpendicular: d2 is orthogonalised
// against d1), for one axis assignment.
Eigen::Isometry3d PoseFromCorner(const Eigen::Vector3d& p1, const Eigen::Vector3d& d1,
                                 const Eigen::Vector3d& d2, const AxisAssignment& assignment,
                                 const BoxDims& dims);

// The eight corners of a box in the camera frame.
std::array<Eigen::Vector3d, 8> BoxCorners(const Eigen::Isometry3d& camera_T_box,
                                          const BoxDims& dims);

// Refines a pose with every observed corner that lies within
// options.corner_match_m of one of the box's predicted corners (the paper's
// refinement), by a least-squares rigid fit (Umeyama) when at least three
// corners match. Returns the number of corners used (0 when unchanged).
int RefineWithCorners(const std::vector<Eigen::Vector3d>& observed_corners, const BoxDims& dims,
                      const PoseOptions& options, Eigen::Isometry3d* camera_T_box);

}  // namespace cornerpose
