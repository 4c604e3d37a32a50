// A Detection as a coloured point cloud (binary little-endian PLY with
// x y z red green blue) that any point cloud viewer opens: the cloud in grey,
// edge points red, each edge segment a dense line in its own blue/cyan shade,
// detected boxes as dense green wireframes, corners as yellow 1 cm crosses.
#pragma once

#include <string>

#include "absl/status/status.h"
#include "common/perception/types.h"

namespace cornerpose {

// Lines are sampled every millimetre. INVALID_ARGUMENT for an inconsistent
// cloud; the write error when the file cannot be written.
absl::Status WriteDetectionPly(const std::string& path, const PointCloud& cloud,
                               const Detection& detection, const BoxDims& dims);

}  // namespace cornerpose
