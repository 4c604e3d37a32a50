#include "common/wire/detector_wire.h"

namespace cornerpose::wire {

void ApplyDetectorOverrides(const v1::DetectorOverrides& overrides, DetectorOptions* options) {
  if (overrides.has_edge_radius_m()) SetEdgeRadius(overrides.edge_radius_m(), options);
  if (overrides.has_edge_threshold()) options->edge_points.threshold = overrides.edge_threshold();
  if (overrides.has_ransac_threshold_m()) {
    options->segments.ransac_threshold_m = overrides.ransac_threshold_m();
  }
  if (overrides.has_tile_uncued_sides()) {
    options->refinement.tile_uncued_sides = overrides.tile_uncued_sides();
  }
}

}  // namespace cornerpose::wire
