// Stage 2: edge segments from edge points (seed paper section 3).
//
// Repeat: RANSAC a line through the remaining edge points; take the inlier
// with the most inlier neighbours as the reference point; walk to the two
// extremities with the paper's Algorithm 1, so a segment stops at a gap wider
// than r_s (two collinear edges of two boxes stay two segments); remove the
// segment's points; until too few points are left.
#pragma once

#include <cstdint>
#include <vector>

#include "absl/status/statusor.h"
#include "common/perception/cancel_token.h"
#include "common/perception/types.h"

namespace cornerpose {

struct EdgeSegmentOptions {
  // RANSAC inlier distance to the line, metres. Paper: 0.01.
  double ransac_threshold_m = 0.01;
  // Neighbourhood radius of Algorithm 1 (r_s): a segment ends at a gap wider
  // than this. Metres. Paper: 0.02.
  double gap_m = 0.02;
  // Line hypotheses tried per segment. Count.
  int ransac_iterations = 120;
  // RANSAC scores hypotheses on at most this many of the remaining points
  // (a random subset); the chosen line is then fitted on all of them. Count.
  int ransac_subset = 1000;
  // The second point of a hypothesis is drawn at this distance from the
  // first, so both tend to lie on one edge. Metres.
  double sample_min_m = 0.03;
  double sample_max_m = 0.15;
  // A segment needs this many points and this length to be kept. Count, metres.
  int min_points = 12;
  double min_length_m = 0.03;
  // Points within this multiple of ransac_threshold_m of a segment are
  // removed with it (edge bands are wider than the RANSAC tube). Unitless, >= 1.
  double removal_scale = 1.5;
  // Stop after this many segments, or this many rejected runs in a row
  // (40 before session 35: on 62 clutter frames no segment came after more
  // than 11 in a row, and the 94 evaluation sets' boxes are the same).
  int max_segments = 200;
  int max_failures = 20;
  // Seed of the random generator: the same input and seed give the same output.
  uint32_t seed = 42;
  // Threads for the RANSAC iterations (the result does not depend on it).
  // Count, [1, 256].
  int num_threads = 1;

  absl::Status Validate() const;
};

// The paper's Algorithm 1 on a set of points along one line. `reference` is
// an index into `points`. A point is an extremity when all its neighbours
// within `radius_m` lie on the reference point's side of it; e1 is the
// extremity nearest the reference and e2 the nearest one on the opposite
// side (the reference itself when there is none). Returns {e1, e2} indices.
std::pair<int, int> FindExtremities(const std::vector<Eigen::Vector3f>& points, int reference,
                                    double radius_m);

namespace internal {
class SharedLoops;
}

// Fits all edge segments in a set of edge points. With `shared`, the RANSAC
// iterations run on it (the caller's thread and whichever threads help;
// options.num_threads is then not used), with the same result. A stopped
// `cancel` ends the fitting after the current RANSAC round (the result is
// then partial: the caller checks the token).
absl::StatusOr<std::vector<EdgeSegment>> FitEdgeSegments(
    const std::vector<Eigen::Vector3f>& edge_points, const EdgeSegmentOptions& options,
    internal::SharedLoops* shared = nullptr, const CancelToken* cancel = nullptr);

}  // namespace cornerpose
