#include "tests/support/pixel_status.h"

#include <cmath>
#include <limits>

namespace cornerpose::testing::internal {

void FinishPixels(std::vector<uint8_t>& status, double min_range_m, double max_range_m,
                  double output_step_m, std::vector<double>& depth, RenderStats* stats) {
  for (size_t i = 0; i < status.size(); ++i) {
    if (status[i] == kValid && !(depth[i] >= min_range_m && depth[i] <= max_range_m)) {
      status[i] = kNoReturn;
    }
    switch (status[i]) {
      case kValid:
        ++stats->valid;
        break;
      case kNoReturn:
        ++stats->no_return;
        break;
      case kShadow:
        ++stats->shadow;
        break;
      case kGrazing:
        ++stats->grazing;
        break;
      case kDropout:
        ++stats->dropout;
        break;
    }
    if (status[i] != kValid) {
      depth[i] = std::numeric_limits<double>::quiet_NaN();
    } else if (output_step_m > 0.0) {
      depth[i] = std::round(depth[i] / output_step_m) * output_step_m;
    }
  }
}

}  // namespace cornerpose::testing::internal
