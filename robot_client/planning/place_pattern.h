// The place pattern: where the k-th picked box goes (a pallet grid, or a
// course of bricks in a wall).
#pragma once

#include <Eigen/Geometry>

#include "absl/status/statusor.h"
#include "robot_client/config/robot_config.h"

namespace cornerpose::robot_client {

// The number of slots: rows * columns * layers.
int SlotCount(const PlacePatternOptions& pattern);

// base_T_slot of slot `slot` (0-based): where that box's bottom centre goes,
// with the origin's orientation. Slots fill row-major within a layer
// (columns along the origin's x vary fastest, rows along its y next), then
// layers along its z:
//   layer = slot / (rows * columns), row = (slot % (rows * columns)) / columns,
//   column = slot % columns,
//   position = base_T_origin * (column * spacing_x_m, row * spacing_y_m,
//                               layer * layer_height_m).
// RESOURCE_EXHAUSTED when slot >= SlotCount (the pattern is full);
// INVALID_ARGUMENT for a negative slot.
absl::StatusOr<Eigen::Isometry3d> SlotPose(const PlacePatternOptions& pattern, int slot);

}  // namespace cornerpose::robot_client
