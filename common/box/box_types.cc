#include "common/box/box_types.h"

#include <cmath>

#include "absl/strings/str_cat.h"

namespace cornerpose {

absl::Status BoxDims::Validate() const {
  const double sides[3] = {l, b, h};
  const char* names[3] = {"l", "b", "h"};
  for (int i = 0; i < 3; ++i) {
    if (!std::isfinite(sides[i]) || sides[i] <= 0.0) {
      return absl::InvalidArgumentError(
          absl::StrCat("box size ", names[i], "=", sides[i], " m must be positive"));
    }
    // Below this no depth camera resolves a box, and the detector's radii
    // derived from the box round to nothing.
    if (sides[i] < 0.005) {
      return absl::InvalidArgumentError(
          absl::StrCat("box size ", names[i], "=", sides[i], " m is below the 5 mm limit"));
    }
    if (sides[i] > 10.0) {
      return absl::InvalidArgumentError(
          absl::StrCat("box size ", names[i], "=", sides[i], " m is above the 10 m limit"));
    }
  }
  return absl::OkStatus();
}

const char* BoxFaceName(BoxFace face) {
  static constexpr const char* kNames[6] = {"+x", "-x", "+y", "-y", "+z", "-z"};
  return kNames[static_cast<int>(face)];
}

Eigen::Vector3d BoxFaceNormal(BoxFace face) {
  const int i = static_cast<int>(face);
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  n[i / 2] = (i % 2 == 0) ? 1.0 : -1.0;
  return n;
}

}  // namespace cornerpose
