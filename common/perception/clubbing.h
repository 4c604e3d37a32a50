// Stage 3: club edge segments of the same box (seed paper Algorithm 2).
//
// Two segments belong to one box when they are perpendicular and meet: their
// lines pass within meet_distance_m of each other (further along the line
// of sight, where the depth noise is), and each segment reaches
// that meeting point (an extremity within end_gap_m of it). The corner is the
// meeting point, the mean of the two lines' closest points, which is where
// the two extremities would meet without the blur of the edge bands.
// Segments linked by such corners form groups (connected components): the
// candidate edges of one box, or of boxes that touch.
#pragma once

#include <vector>

#include "absl/status/statusor.h"
#include "common/perception/types.h"

namespace cornerpose {

struct ClubbingOptions {
  // Largest deviation from 90 degrees between two clubbed segments. Degrees.
  double perpendicular_tolerance_deg = 10.0;
  // The two segments' lines must pass this close to each other. Metres.
  // Paper: 0.01.
  double meet_distance_m = 0.01;
  // ... across the line of sight to their meeting point; along it they may
  // pass this many times as far apart. The depth noise lies along the ray
  // (an active stereo camera's, at 1.6 m, puts the two lines of one corner
  // of a brick 1-3 cm apart in depth), while across it the edge points pin
  // a line to a few millimetres. The camera sits at the cloud's origin.
  // The detector keeps it only for frames with a registered colour image
  // (DetectBoxes: without one, 1 unless the caller set it). 1: the paper's
  // sphere. Unitless, [1, 10].
  double meet_along_view_factor = 3.0;
  // Each segment's nearer extremity must lie this close to the meeting
  // point; edge bands and fillets keep extremities a little short of the
  // true corner. Metres.
  double end_gap_m = 0.03;

  absl::Status Validate() const;
};

struct SegmentGroups {
  std::vector<Corner> corners;
  std::vector<std::vector<int>> groups;  // segment indices per group, groups of >= 2
};

// Tests one pair; fills `corner` when they meet.
bool SegmentsMeet(const std::vector<EdgeSegment>& segments, int a, int b,
                  const ClubbingOptions& options, Corner* corner);

absl::StatusOr<SegmentGroups> ClubSegments(const std::vector<EdgeSegment>& segments,
                                           const ClubbingOptions& options);

}  // namespace cornerpose
