#include "common/perception/types.h"

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

absl::Status CameraIntrinsics::Validate() const {
  if (width <= 0 || height <= 0 || width > 16384 || height > 16384) {
    return absl::InvalidArgumentError(
        absl::StrCat("intrinsics image size ", width, " x ", height, " is out of (0, 16384]"));
  }
  if (!(fx > 0.0) || !(fy > 0.0) || !std::isfinite(fx) || !std::isfinite(fy)) {
    return absl::InvalidArgumentError(
        absl::StrCat("intrinsics focal lengths fx=", fx, " fy=", fy, " must be positive"));
  }
  if (!std::isfinite(cx) || !std::isfinite(cy)) {
    return absl::InvalidArgumentError("intrinsics principal point is not finite");
  }
  return absl::OkStatus();
}

}  // namespace cornerpose
