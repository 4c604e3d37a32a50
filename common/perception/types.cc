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

}  // namespace cornerpose
