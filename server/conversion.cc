#include "server/conversion.h"

#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "common/io/cloud_io.h"

namespace cornerpose::server {
namespace {

// The wire format is little-endian; reading it with memcpy is only right on
// a little-endian host, which every target of this service is.
static_assert(std::endian::native == std::endian::little,
              "conversion.cc reads little-endian wire data with memcpy");

constexpr size_t kBytesPerPoint = 3 * sizeof(float);

// width * height, or an error naming both when it is not the point count.
absl::Status CheckGrid(uint64_t width, uint64_t height, uint64_t count, absl::string_view what) {
  if (width * height != count) {
    return absl::InvalidArgumentError(absl::StrCat(what, " width * height (", width, " * ", height,
                                                   " = ", width * height, ") does not match its ",
                                                   count, " points"));
  }
  return absl::OkStatus();
}

}  // namespace

v1::PointCloud CloudToProto(const PointCloud& cloud) {
  v1::PointCloud msg;
  std::string bytes(cloud.size() * kBytesPerPoint, '\0');
  for (size_t i = 0; i < cloud.size(); ++i) {
    const float p[3] = {cloud.xyz[i].x(), cloud.xyz[i].y(), cloud.xyz[i].z()};
    std::memcpy(bytes.data() + i * kBytesPerPoint, p, kBytesPerPoint);
  }
  msg.set_xyz(std::move(bytes));
  msg.set_width(static_cast<uint32_t>(cloud.width));
  msg.set_height(static_cast<uint32_t>(cloud.height));
  return msg;
}

absl::StatusOr<PointCloud> CloudFromProto(const v1::PointCloud& cloud) {
  const std::string& bytes = cloud.xyz();
  if (bytes.size() % kBytesPerPoint != 0) {
    return absl::InvalidArgumentError(
        absl::StrCat("cloud xyz has ", bytes.size(),
                     " bytes, not a multiple of 12 (3 little-endian float32 per point)"));
  }
  const uint64_t count = bytes.size() / kBytesPerPoint;
  if (count > kMaxPoints) {
    return absl::InvalidArgumentError(
        absl::StrCat("cloud has ", count, " points, above the limit of ", kMaxPoints));
  }
  if (absl::Status s = CheckGrid(cloud.width(), cloud.height(), count, "cloud"); !s.ok()) return s;

  PointCloud out;
  out.width = static_cast<int>(cloud.width());
  out.height = static_cast<int>(cloud.height());
  out.xyz.resize(count);
  // Eigen::Vector3f is three packed floats; copy point by point so nothing
  // depends on that.
  for (uint64_t i = 0; i < count; ++i) {
    float p[3];
    std::memcpy(p, bytes.data() + i * kBytesPerPoint, kBytesPerPoint);
    out.xyz[i] = Eigen::Vector3f(p[0], p[1], p[2]);
  }
  return out;
}

absl::StatusOr<CameraIntrinsics> IntrinsicsFromProto(const v1::CameraIntrinsics& in) {
  constexpr uint32_t kMaxSide = 1 << 16;  // pixels; far above any depth camera
  if (in.width() == 0 || in.height() == 0 || in.width() > kMaxSide || in.height() > kMaxSide) {
    return absl::InvalidArgumentError(absl::StrCat("intrinsics size ", in.width(), " x ",
                                                   in.height(), " must be within 1..", kMaxSide,
                                                   " pixels per side"));
  }
  CameraIntrinsics out;
  out.width = static_cast<int>(in.width());
  out.height = static_cast<int>(in.height());
  out.fx = in.fx();
  out.fy = in.fy();
  out.cx = in.cx();
  out.cy = in.cy();
  if (absl::Status s = out.Validate(); !s.ok()) return s;
  return out;
}

absl::StatusOr<PointCloud> CloudFromDepthImage(const v1::DepthImage& image,
                                               const v1::CameraIntrinsics* intrinsics) {
  if (intrinsics == nullptr) {
    return absl::InvalidArgumentError("depth_image needs intrinsics (fx, fy, cx, cy, size)");
  }
  absl::StatusOr<CameraIntrinsics> camera = IntrinsicsFromProto(*intrinsics);
  if (!camera.ok()) return camera.status();
  if (image.width() != intrinsics->width() || image.height() != intrinsics->height()) {
    return absl::InvalidArgumentError(absl::StrCat(
        "depth_image is ", image.width(), " x ", image.height(), " but the intrinsics are for ",
        intrinsics->width(), " x ", intrinsics->height()));
  }
  const uint64_t pixels = uint64_t{image.width()} * image.height();
  if (pixels > kMaxPoints) {
    return absl::InvalidArgumentError(
        absl::StrCat("depth_image has ", pixels, " pixels, above the limit of ", kMaxPoints));
  }

  size_t sample_bytes = 0;
  switch (image.encoding()) {
    case v1::DEPTH_ENCODING_UINT16_MM:
      sample_bytes = sizeof(uint16_t);
      break;
    case v1::DEPTH_ENCODING_FLOAT32_M:
      sample_bytes = sizeof(float);
      break;
    default:
      return absl::InvalidArgumentError(
          absl::StrCat("depth_image encoding ", image.encoding(),
                       " is not DEPTH_ENCODING_UINT16_MM or DEPTH_ENCODING_FLOAT32_M"));
  }
  if (image.data().size() != pixels * sample_bytes) {
    return absl::InvalidArgumentError(absl::StrCat(
        "depth_image data has ", image.data().size(), " bytes; ", image.width(), " x ",
        image.height(), " samples of ", sample_bytes, " bytes need ", pixels * sample_bytes));
  }

  if (image.encoding() == v1::DEPTH_ENCODING_UINT16_MM) {
    std::vector<uint16_t> depth(pixels);
    std::memcpy(depth.data(), image.data().data(), image.data().size());
    return DepthToCloud(depth, *camera, /*depth_scale_m=*/0.001);
  }

  // float32 metres: the same back-projection as DepthToCloud, without the
  // rounding to millimetres that a uint16 detour would add.
  PointCloud cloud;
  cloud.width = camera->width;
  cloud.height = camera->height;
  cloud.xyz.resize(pixels);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int v = 0; v < camera->height; ++v) {
    for (int u = 0; u < camera->width; ++u) {
      const size_t i = static_cast<size_t>(v) * camera->width + u;
      float z;
      std::memcpy(&z, image.data().data() + i * sizeof(float), sizeof(float));
      if (!std::isfinite(z) || z <= 0.0f) {
        cloud.xyz[i] = Eigen::Vector3f(nan, nan, nan);
        continue;
      }
      cloud.xyz[i] = Eigen::Vector3f(static_cast<float>((u - camera->cx) * z / camera->fx),
                                     static_cast<float>((v - camera->cy) * z / camera->fy), z);
    }
  }
  return cloud;
}

BoxDims BoxDimsFromProto(const v1::BoxDimensions& box) { return {box.l(), box.b(), box.h()}; }

v1::Vector3 ToProto(const Eigen::Vector3d& v) {
  v1::Vector3 out;
  out.set_x(v.x());
  out.set_y(v.y());
  out.set_z(v.z());
  return out;
}

v1::Vector3 ToProto(const Eigen::Vector3f& v) { return ToProto(Eigen::Vector3d(v.cast<double>())); }

v1::Quaternion ToProto(const Eigen::Quaterniond& q) {
  Eigen::Quaterniond unit = q.normalized();
  if (unit.w() < 0.0) unit.coeffs() = -unit.coeffs();
  v1::Quaternion out;
  out.set_w(unit.w());
  out.set_x(unit.x());
  out.set_y(unit.y());
  out.set_z(unit.z());
  return out;
}

v1::Pose ToProto(const Eigen::Isometry3d& parent_T_child) {
  v1::Pose out;
  *out.mutable_position() = ToProto(Eigen::Vector3d(parent_T_child.translation()));
  *out.mutable_orientation() = ToProto(Eigen::Quaterniond(parent_T_child.rotation()));
  return out;
}

v1::BoxFace ToProto(BoxFace face) {
  switch (face) {
    case BoxFace::kPlusX:
      return v1::BOX_FACE_PLUS_X;
    case BoxFace::kMinusX:
      return v1::BOX_FACE_MINUS_X;
    case BoxFace::kPlusY:
      return v1::BOX_FACE_PLUS_Y;
    case BoxFace::kMinusY:
      return v1::BOX_FACE_MINUS_Y;
    case BoxFace::kPlusZ:
      return v1::BOX_FACE_PLUS_Z;
    case BoxFace::kMinusZ:
      return v1::BOX_FACE_MINUS_Z;
  }
  return v1::BOX_FACE_UNSPECIFIED;
}

v1::DetectResponse DetectionToProto(const Detection& detection, bool include_edge_points) {
  v1::DetectResponse out;
  for (const DetectedBox& box : detection.boxes) {
    v1::DetectedBox* b = out.add_boxes();
    *b->mutable_camera_pose_box() = ToProto(box.camera_T_box);
    b->set_score(box.score);
    b->set_grasp_face(ToProto(box.grasp_face));
    *b->mutable_grasp_centre() = ToProto(box.grasp_centre_camera);
    *b->mutable_grasp_normal() = ToProto(box.grasp_normal_camera);
  }
  for (const EdgeSegment& segment : detection.segments) {
    v1::EdgeSegment* s = out.add_segments();
    *s->mutable_end1() = ToProto(segment.end1);
    *s->mutable_end2() = ToProto(segment.end2);
    s->set_num_points(static_cast<uint32_t>(segment.num_points));
  }
  for (const Corner& corner : detection.corners) {
    *out.add_corners()->mutable_position() = ToProto(corner.position);
  }
  if (include_edge_points) {
    out.mutable_edge_points()->Reserve(static_cast<int>(detection.edge_points.size()));
    for (const Eigen::Vector3f& p : detection.edge_points) *out.add_edge_points() = ToProto(p);
  }
  v1::StageTimings* t = out.mutable_timings();
  t->set_preprocess_ms(detection.timings.preprocess_ms);
  t->set_edge_points_ms(detection.timings.edge_points_ms);
  t->set_edge_segments_ms(detection.timings.edge_segments_ms);
  t->set_clubbing_ms(detection.timings.clubbing_ms);
  t->set_poses_ms(detection.timings.poses_ms);
  t->set_total_ms(detection.timings.total_ms);
  return out;
}

void AddFrameToProto(const Frame& frame, const FrameContents& contents,
                     v1::DetectResponse* response) {
  response->set_frame_id(frame.id);
  response->set_capture_time_unix_nanos(absl::ToUnixNanos(frame.capture_time));
  response->set_source(frame.source);
  if (contents.include_cloud) *response->mutable_cloud() = CloudToProto(frame.cloud);
}

}  // namespace cornerpose::server
