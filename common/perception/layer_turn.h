// Boxes side by side on one layer share its turn. A box's in-plane turn is
// read from its own sides: on a layer of touching boxes mostly seams,
// whose turn is read over a short side (a brick's 9 cm) at most 2 degrees a
// refinement step, so a brick pallet's boxes come out 2-5 degrees off, and
// now and then 10 (a neighbour proposed from a turned reading). Touching
// boxes on one layer press their sides together and are parallel (or at a
// right angle, in an interlocked layer): a returned box whose face touches
// at least min_agreeing others on its plane that agree on their turn (mod
// 90 degrees, within agree_deg) takes the median of theirs and its own,
// turned about its face centre, when that differs from its own by more
// than min_turn_deg and at most max_turn_deg. Turns only (the position of
// its face centre and its plane stay), never which boxes are returned.
// Applied after the shared layer planes (layer_plane.h).
#pragma once

#include <vector>

#include "absl/status/status.h"
#include "common/perception/types.h"

namespace cornerpose {

struct LayerTurnOptions {
  // Touching faces on the face's plane that must agree on their turn.
  // Count, [0, 100]; 0 turns the sharing off.
  int min_agreeing = 3;
  // Turns (mod 90 degrees) within this of one another agree. Degrees,
  // (0, 10].
  double agree_deg = 2.0;
  // A box is turned only when the layer's turn differs from its own by
  // more than this (a smaller difference is the layer's own spread) and at
  // most max_turn_deg (a box turned further is not lying in the layer's
  // pattern, whatever touches it). Degrees, [0, 45].
  double min_turn_deg = 2.0;
  double max_turn_deg = 12.0;
  // Two faces are on one plane when their normals are within this and each
  // centre lies within plane_tolerance_m of the other's plane; they touch
  // when their centres are closer than touch_factor times the sum of their
  // half diagonals (LayerPlaneOptions' defaults). Degrees [0, 30], metres
  // (0, 0.1], unitless (0, 2].
  double max_normal_deg = 12.0;
  double plane_tolerance_m = 0.012;
  double touch_factor = 1.15;

  absl::Status Validate() const;
};

// Turns the boxes of *boxes that lie in a layer of touching boxes agreeing
// on their turn to the layer's turn (pose only). Returns how many turned.
int AlignToLayerTurns(const BoxDims& dims, const LayerTurnOptions& options,
                      std::vector<DetectedBox>* boxes);

}  // namespace cornerpose
