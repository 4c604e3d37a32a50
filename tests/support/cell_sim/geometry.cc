#include "tests/support/cell_sim/geometry.h"

#include "tests/support/obb.h"

namespace cornerpose::cell_sim {

bool BoxesOverlap(const Obb& a, const Obb& b, double tolerance_m) {
  if (!BoundsOf(a).Overlaps(BoundsOf(b))) return false;
  return testing::ObbSeparation(a.dims, a.world_T_box, b.dims, b.world_T_box) < -tolerance_m;
}

double LowestZ(const Obb& box) { return BoundsOf(box).min.z(); }

}  // namespace cornerpose::cell_sim
