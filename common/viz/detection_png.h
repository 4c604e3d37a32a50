// A Detection drawn over the depth image, as an RGB PNG: depth in grey (near
// = bright, no return = black), detected box wireframes green (all 12 edges)
// with the box index in magenta, edge points red, edge segments blue, corners
// as yellow crosses.
#pragma once

#include <string>

#include "absl/status/status.h"
#include "common/perception/types.h"

namespace cornerpose {

// The image is camera.width x camera.height. An organized cloud of that size
// is drawn from its grid; any other cloud is projected with the intrinsics
// into a z-buffer. INVALID_ARGUMENT for bad intrinsics or an inconsistent
// cloud; the write error when the file cannot be written.
absl::Status WriteDetectionPng(const std::string& path, const PointCloud& cloud,
                               const CameraIntrinsics& camera, const Detection& detection,
                               const BoxDims& dims);

}  // namespace cornerpose
