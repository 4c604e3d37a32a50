#include "robot_client/planning/place_pattern.h"

#include "absl/strings/str_cat.h"

namespace cornerpose::robot_client {

int SlotCount(const PlacePatternOptions& pattern) {
  if (pattern.rows < 1 || pattern.columns < 1 || pattern.layers < 1) return 0;
  return pattern.rows * pattern.columns * pattern.layers;
}

absl::StatusOr<Eigen::Isometry3d> SlotPose(const PlacePatternOptions& pattern, int slot) {
  if (slot < 0) return absl::InvalidArgumentError(absl::StrCat("slot ", slot, " is negative"));
  const int count = SlotCount(pattern);
  if (slot >= count) {
    return absl::ResourceExhaustedError(
        absl::StrCat("the place pattern is full: slot ", slot, " of ", count, " (", pattern.rows,
                     " rows x ", pattern.columns, " columns x ", pattern.layers, " layers)"));
  }
  const int per_layer = pattern.rows * pattern.columns;
  const int layer = slot / per_layer;
  const int row = (slot % per_layer) / pattern.columns;
  const int column = slot % pattern.columns;
  const Eigen::Vector3d origin_p(column * pattern.spacing_x_m, row * pattern.spacing_y_m,
                                 layer * pattern.layer_height_m);
  Eigen::Isometry3d base_T_slot = pattern.base_T_origin;
  base_T_slot.translation() = pattern.base_T_origin * origin_p;
  return base_T_slot;
}

}  // namespace cornerpose::robot_client
