// Stage 1: edge points by the seed paper's neighbourhood score (section 2).
//
// For a point p with neighbours n_j within r_s, d_j = (n_j - p)/|n_j - p| and
// s(p) = |sum_j d_j| / k. A flat interior scores ~0, a free boundary ~2/pi
// (0.64), a 90 degree crease ~0.45; p is an edge point when s(p) > t_h.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "absl/status/statusor.h"
#include "common/perception/cancel_token.h"
#include "common/perception/types.h"

namespace cornerpose {

struct EdgePointOptions {
  // r_s: neighbourhood radius, metres. Paper: 0.02.
  double radius_m = 0.02;
  // t_h: a point is an edge point when its score exceeds this. Paper: 0.35.
  double threshold = 0.35;
  // Neighbours sampled per point on organized frames (a fixed sunflower
  // pattern over the pixel disc that r_s covers at the point's depth); 0 uses
  // every pixel in the disc, the paper's full neighbourhood. Unitless.
  int max_samples = 64;
  // Points with fewer neighbours than this are not scored (isolated returns
  // and flying pixels have almost none). Count.
  int min_neighbours = 6;
  // Organized frames only: drop a point when a sample within 2 r_s in the
  // image lies this much closer to the camera. Such a point is on the far,
  // occluded side of a depth jump (a shadow border, the floor behind a box),
  // which scores as a boundary but is no edge of the surface it lies on.
  // Metres; 0 disables.
  double occluded_side_jump_m = 0.03;
  // Score each point from the median depth of its neighbours rather than
  // its own noisy depth (see edge_points.cc); assumes a cloud in the frame of
  // the camera that took it. Off gives the paper's formula exactly.
  bool denoise = true;
  // Organized frames only: score one pixel in coarse_step x coarse_step
  // first, then every pixel next to a coarse hit; 1 scores every pixel (the
  // full-resolution reference). Pixels.
  int coarse_step = 3;
  // Organized frames only: score the pixels of every lattice_px-th row and
  // column (each with its whole neighbourhood at full resolution), so the
  // edge points are those of every pixel on that lattice. 1 scores every
  // pixel; DetectorOptions::edge_lattice_radius_px chooses it from the
  // frame. Pixels, [1, 8].
  int lattice_px = 1;
  // The coarse pass keeps cells scoring above threshold * this, so pixels
  // at the rim of an edge band are not lost. Unitless, in (0, 1].
  double coarse_threshold_factor = 0.85;
  // A cell next to a coarse hit is scored at full resolution only when its
  // own centre scored above threshold * this (or could not be scored): edge
  // scores fall off smoothly across a band, so a cell whose centre scores
  // far below t_h holds no band pixel, and most of the cells around the
  // hits are flat surface. 0 scores every cell next to a hit: 0.5 saves
  // ~15 % of the stage and loses ~0.5 % of the edge points, which on noisy
  // stereo frames changed which boxes were found. Unitless, [0, 1].
  double coarse_skip_factor = 0.0;
  // Worker threads for the per-point loop. Count, >= 1.
  int num_threads = 2;

  absl::Status Validate() const;
};

struct EdgePoints {
  std::vector<Eigen::Vector3f> points;  // camera frame, metres
  std::vector<int> indices;             // index of each edge point in the input cloud
  std::vector<float> scores;            // s(p) of each edge point
  // Unorganized clouds (the k-d tree path) only, a measure of the work done:
  // points in the k-d tree (one per voxel of r_s / 8) and neighbours the
  // radius searches returned, summed over all points.
  size_t kdtree_points = 0;
  int64_t neighbours_examined = 0;
};

// The most finite points the k-d tree path scores; more is INVALID_ARGUMENT.
inline constexpr size_t kMaxKdTreePoints = 1'000'000;

// Scores one point against an explicit neighbour list (the paper's formula).
// Neighbours equal to p are ignored. Returns 0 with no usable neighbour.
float EdgeScore(const Eigen::Vector3f& p, const std::vector<Eigen::Vector3f>& neighbours);

// Finds the edge points of a cloud. Organized clouds (height > 1) use the
// pixel grid for neighbour search and need the camera's focal length (pixels),
// which EstimateIntrinsics() can recover from the cloud itself; unorganized
// clouds use a k-d tree over the neighbours within r_s, as in the paper, but
// at most one per voxel of r_s / 8, so that no pile of points makes the
// search quadratic. A stopped `cancel` ends the scoring early (the result is
// then partial: the caller checks the token).
absl::StatusOr<EdgePoints> DetectEdgePoints(const PointCloud& cloud,
                                            const EdgePointOptions& options,
                                            double focal_px = 525.0,
                                            const CancelToken* cancel = nullptr);

}  // namespace cornerpose
