#include "common/perception/types.h"

#include <utility>

#include "absl/strings/str_cat.h"

namespace cornerpose {

absl::Status PointCloud::Validate() const {
  if (width < 0 || height < 0) {
    return absl::InvalidArgumentError(
        absl::StrCat("cloud size ", width, " x ", height, " is negative"));
  }
  if ((width == 0) != (height == 0)) {
    return absl::InvalidArgumentError(
        absl::StrCat("cloud size ", width, " x ", height, ": one side is zero"));
  }
  if (static_cast<size_t>(width) * static_cast<size_t>(height) != xyz.size()) {
    return absl::InvalidArgumentError(
        absl::StrCat("cloud is ", width, " x ", height, " but holds ", xyz.size(), " points"));
  }
  if (!rgb.empty() && rgb.size() != xyz.size()) {
    return absl::InvalidArgumentError(
        absl::StrCat("cloud has ", xyz.size(), " points but ", rgb.size(), " colours"));
  }
  return absl::OkStatus();
}

// Plausible ranges: sides (0, 16384]; fx, fy [1, 1e5] px; cx, cy [-1e5, 1e5]
// px (a crop may put the principal point outside its own image).
absl::Status CameraIntrinsics::Validate() const {
  if (width <= 0 || height <= 0 || width > 16384 || height > 16384) {
    return absl::InvalidArgumentError(
        absl::StrCat("intrinsics image size ", width, " x ", height, " is out of (0, 16384]"));
  }
  constexpr double kMaxPixels = 1e5;
  for (const auto& [name, value] : {std::pair{"fx", fx}, std::pair{"fy", fy}}) {
    if (!(value >= 1.0 && value <= kMaxPixels)) {
      return absl::InvalidArgumentError(
          absl::StrCat("intrinsics ", name, "=", value, " px is outside [1, ", kMaxPixels, "]"));
    }
  }
  for (const auto& [name, value] : {std::pair{"cx", cx}, std::pair{"cy", cy}}) {
    if (!(std::abs(value) <= kMaxPixels)) {
      return absl::InvalidArgumentError(absl::StrCat("intrinsics ", name, "=", value,
                                                     " px is outside [-", kMaxPixels, ", ",
                                                     kMaxPixels, "]"));
    }
  }
  return absl::OkStatus();
}

absl::Status BoxDims::Validate() const {
  const double sides[3] = {l, b, h};
  const char* names[3] = {"l", "b", "h"};
  for (int i = 0; i < 3; ++i) {
    if (!std::isfinite(sides[i]) || sides[i] <= 0.0) {
      return absl::InvalidArgumentError(
          absl::StrCat("box size ", names[i], "=", sides[i], " m must be positive"));
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
