// Faces between two parallel edge segments: the opposite sides of a box's
// face, seen where neither of its corners is. In a heap a box's long sides
// often show as edges (a depth jump to the floor or to the box below) while
// its ends do not (an end against a neighbour, or too short for a segment of
// its own), so the corners the paper's poses start from are missing. Two
// segments that run parallel, face each other and lie a side of the box
// apart bound a face across; its other side is the one their lengths allow,
// anchored at either end of what the two segments span. The judge decides:
// every pose proposed here is refined and tested like a corner's.
#pragma once

#include <Eigen/Geometry>
#include <vector>

#include "absl/status/status.h"
#include "common/perception/types.h"

namespace cornerpose {

struct EdgePairOptions {
  // Off: no pair proposes a face.
  bool enabled = true;
  // The two segments' directions within this of each other. Degrees.
  double max_angle_deg = 8.0;
  // Their distance apart (across, in the plane they span) within this of a
  // side of the box. Metres.
  double width_tolerance_m = 0.015;
  // Each segment at least this long, and along the other over at least
  // min_overlap of the shorter one: they face each other. Metres, unitless.
  double min_length_m = 0.04;
  double min_overlap = 0.5;
  // A segment longer than a side by more than this is not that side.
  // Metres.
  double length_tolerance_m = 0.025;

  absl::Status Validate() const;
};

struct EdgePairFace {
  Eigen::Isometry3d camera_T_box = Eigen::Isometry3d::Identity();
  int segment_a = -1, segment_b = -1;  // indices into the segment list
};

// The poses the parallel pairs of `segments` propose (each pair a face of
// the box across them, anchored at each end of their span), in pair order.
std::vector<EdgePairFace> ProposeFromEdgePairs(const std::vector<EdgeSegment>& segments,
                                               const BoxDims& dims, const EdgePairOptions& options);

}  // namespace cornerpose
