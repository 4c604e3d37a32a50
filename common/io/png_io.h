// PNG files through libpng: 16-bit depth images in and out, 8-bit RGB images
// for debug views. Every libpng failure comes back as a status, never a
// longjmp past the caller or a crash.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"

namespace cornerpose {

// Largest side accepted when reading, as for CameraIntrinsics.
inline constexpr int kMaxPngSide = 16384;

// Reads a 16-bit single-channel PNG (a depth image; units are the caller's).
// Row-major, index v * width + u. NOT_FOUND when the file is missing,
// INVALID_ARGUMENT when it is not a PNG or not 16-bit grey.
absl::StatusOr<std::vector<uint16_t>> ReadDepthPng(const std::string& path, int* width,
                                                   int* height);

// Writes a 16-bit single-channel PNG. depth.size() must be width * height.
absl::Status WriteDepthPng(const std::string& path, const std::vector<uint16_t>& depth, int width,
                           int height);

// Writes an 8-bit RGB PNG; rgb holds width * height * 3 bytes, row-major.
absl::Status WriteRgbPng(const std::string& path, const std::vector<uint8_t>& rgb, int width,
                         int height);

// Reads any PNG as 8-bit RGB (grey, palette, alpha and 16-bit are converted),
// width * height * 3 bytes. For tests and tools that inspect debug images.
absl::StatusOr<std::vector<uint8_t>> ReadRgbPng(const std::string& path, int* width, int* height);

}  // namespace cornerpose
