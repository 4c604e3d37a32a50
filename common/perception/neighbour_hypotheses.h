// Hypotheses for the boxes next to a confirmed one. In a pallet layer the
// seams between touching boxes leave almost no depth signal, so few edges and
// corners are found inside the layer; but a confirmed box's side is also its
// neighbour's side, and the known size says where that neighbour ends. Each
// neighbour is proposed in the same orientation and turned a quarter about
// the grasp face's normal (aligned with either end of the shared side); the
// caller checks every proposal against the depth image like any other.
#pragma once

#include <vector>

#include "common/perception/types.h"

namespace cornerpose {

// Poses of the boxes that would touch `box` side by side across each of the
// four sides of its grasp face, `gap_m` apart (metres); with `layer_down`,
// also the same-orientation ones a box height lower (a pallet stacked at two
// heights: the lower layer beside an upper box).
std::vector<Eigen::Isometry3d> NeighbourHypotheses(const DetectedBox& box, const BoxDims& dims,
                                                   double gap_m, bool layer_down = false);

}  // namespace cornerpose
