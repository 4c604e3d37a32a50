// The one place protobuf messages and the detector's types convert. Every
// input from the wire is validated here, with a message that names the field
// and the value, before the detector sees it.
#pragma once

#include <Eigen/Geometry>

#include "absl/status/statusor.h"
#include "common/perception/types.h"
#include "cornerpose/v1/geometry.pb.h"
#include "cornerpose/v1/perception_service.pb.h"
#include "server/sources/frame_source.h"

namespace cornerpose::server {

// Larger clouds and images are refused (the detector's own limit). Points.
inline constexpr uint64_t kMaxPoints = 20'000'000;

// Unpacks little-endian float32 xyz. INVALID_ARGUMENT when the byte length is
// not a multiple of 12, width * height differs from the point count, or the
// cloud has more than kMaxPoints points. An all-empty message is an empty
// cloud.
absl::StatusOr<PointCloud> CloudFromProto(const v1::PointCloud& cloud);

// Packs xyz as little-endian float32 triples, keeping width x height (and
// the NaNs of an organized cloud): the inverse of CloudFromProto. Clients
// send clouds with it; the server returns a source's frame with it.
v1::PointCloud CloudToProto(const PointCloud& cloud);

// INVALID_ARGUMENT unless the size is positive and the focal lengths are
// positive and finite.
absl::StatusOr<CameraIntrinsics> IntrinsicsFromProto(const v1::CameraIntrinsics& intrinsics);

// Back-projects a depth image into an organized cloud through `intrinsics`,
// which is required (nullptr: INVALID_ARGUMENT) and must match the image
// size. INVALID_ARGUMENT also for an unspecified encoding or a data length
// that is not width * height samples.
absl::StatusOr<PointCloud> CloudFromDepthImage(const v1::DepthImage& image,
                                               const v1::CameraIntrinsics* intrinsics);

// Not validated: BoxDims::Validate says what is wrong with which side.
BoxDims BoxDimsFromProto(const v1::BoxDimensions& box);

v1::Vector3 ToProto(const Eigen::Vector3d& v);
v1::Vector3 ToProto(const Eigen::Vector3f& v);
// The rotation as a unit quaternion with w >= 0 (q and -q are the same
// rotation; one sign keeps responses comparable).
v1::Quaternion ToProto(const Eigen::Quaterniond& q);
v1::Pose ToProto(const Eigen::Isometry3d& parent_T_child);
v1::BoxFace ToProto(BoxFace face);

// Boxes, segments, corners and timings; the edge points only when asked.
v1::DetectResponse DetectionToProto(const Detection& detection, bool include_edge_points);

// What a response about a source's frame carries besides the detection.
struct FrameContents {
  bool include_cloud = false;  // the frame's cloud (large)
};

// Sets the frame's id, capture time and source on `response`, and its cloud
// when asked.
void AddFrameToProto(const Frame& frame, const FrameContents& contents,
                     v1::DetectResponse* response);

}  // namespace cornerpose::server
