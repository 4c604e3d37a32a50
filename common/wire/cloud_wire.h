// Clouds, depth images, colour images and camera intrinsics between protobuf
// (cornerpose/v1/geometry.proto) and the detector's types, both ways. Every
// input from the wire is validated here, with a message that names the field
// and the value, before the detector sees it.
#pragma once

#include <cstdint>
#include <vector>

#include "absl/status/statusor.h"
#include "common/perception/types.h"
#include "cornerpose/v1/geometry.pb.h"

namespace cornerpose::wire {

// Unpacks little-endian float32 xyz, and the colour when `rgb` is set (3
// bytes R, G, B per point). INVALID_ARGUMENT when the byte length is not a
// multiple of 12, width * height differs from the point count, the cloud
// has more than kMaxPoints points, or rgb is not 3 bytes per point. An
// all-empty message is an empty cloud.
absl::StatusOr<PointCloud> CloudFromProto(const v1::PointCloud& cloud);

// Packs xyz as little-endian float32 triples, keeping width x height (and
// the NaNs of an organized cloud), and the colour when the cloud has one:
// the inverse of CloudFromProto.
v1::PointCloud CloudToProto(const PointCloud& cloud);

// INVALID_ARGUMENT unless the size is positive and the focal lengths are
// positive and finite.
absl::StatusOr<CameraIntrinsics> IntrinsicsFromProto(const v1::CameraIntrinsics& intrinsics);
v1::CameraIntrinsics ToProto(const CameraIntrinsics& intrinsics);

// Back-projects a depth image into an organized cloud through `intrinsics`,
// which is required (nullptr: INVALID_ARGUMENT) and must match the image
// size. INVALID_ARGUMENT also for an unspecified encoding or a data length
// that is not width * height samples.
absl::StatusOr<PointCloud> CloudFromDepthImage(const v1::DepthImage& image,
                                               const v1::CameraIntrinsics* intrinsics);

// A colour image registered to a width x height cloud, as PointCloud::rgb
// (packed 0x00RRGGBB; grey g becomes 0x00gggggg). INVALID_ARGUMENT naming
// `color` for another size, an unspecified encoding or a data length that
// is not width * height pixels.
absl::StatusOr<std::vector<uint32_t>> ColorFromProto(const v1::ColorImage& color, int width,
                                                     int height);

}  // namespace cornerpose::wire
