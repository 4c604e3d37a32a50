#include "common/wire/cloud_wire.h"

#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>

#include "absl/strings/str_cat.h"
#include "common/io/cloud_io.h"
#include "common/perception/detector.h"

namespace cornerpose::wire {
namespace {

// The wire format is little-endian; reading it with memcpy is only right on
// a little-endian host, which every target of this service is.
static_assert(std::endian::native == std::endian::little,
              "cloud_wire.cc reads little-endian wire data with memcpy");

constexpr size_t kBytesPerPoint = 3 * sizeof(float);
constexpr size_t kBytesPerColour = 3;

uint32_t PackRgb(uint8_t r, uint8_t g, uint8_t b) {
  return (uint32_t{r} << 16) | (uint32_t{g} << 8) | uint32_t{b};
}

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
  if (cloud.has_color()) {
    std::string rgb(cloud.rgb.size() * kBytesPerColour, '\0');
    for (size_t i = 0; i < cloud.rgb.size(); ++i) {
      rgb[i * 3 + 0] = static_cast<char>((cloud.rgb[i] >> 16) & 0xff);
      rgb[i * 3 + 1] = static_cast<char>((cloud.rgb[i] >> 8) & 0xff);
      rgb[i * 3 + 2] = static_cast<char>(cloud.rgb[i] & 0xff);
    }
    msg.set_rgb(std::move(rgb));
  }
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
  if (!cloud.rgb().empty() && cloud.rgb().size() != count * kBytesPerColour) {
    return absl::InvalidArgumentError(absl::StrCat("cloud rgb has ", cloud.rgb().size(), " bytes; ",
                                                   count, " points of 3 bytes need ",
                                                   count * kBytesPerColour));
  }

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
  if (!cloud.rgb().empty()) {
    const auto* c = reinterpret_cast<const uint8_t*>(cloud.rgb().data());
    out.rgb.resize(count);
    for (uint64_t i = 0; i < count; ++i) out.rgb[i] = PackRgb(c[3 * i], c[3 * i + 1], c[3 * i + 2]);
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

v1::CameraIntrinsics ToProto(const CameraIntrinsics& intrinsics) {
  v1::CameraIntrinsics out;
  out.set_width(static_cast<uint32_t>(intrinsics.width));
  out.set_height(static_cast<uint32_t>(intrinsics.height));
  out.set_fx(intrinsics.fx);
  out.set_fy(intrinsics.fy);
  out.set_cx(intrinsics.cx);
  out.set_cy(intrinsics.cy);
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

absl::StatusOr<std::vector<uint32_t>> ColorFromProto(const v1::ColorImage& color, int width,
                                                     int height) {
  if (color.width() != static_cast<uint32_t>(width) ||
      color.height() != static_cast<uint32_t>(height)) {
    return absl::InvalidArgumentError(absl::StrCat("color is ", color.width(), " x ",
                                                   color.height(), " but the cloud is ", width,
                                                   " x ", height, " (it must be registered)"));
  }
  size_t pixel_bytes = 0;
  switch (color.encoding()) {
    case v1::COLOR_ENCODING_RGB8:
      pixel_bytes = 3;
      break;
    case v1::COLOR_ENCODING_GRAY8:
      pixel_bytes = 1;
      break;
    default:
      return absl::InvalidArgumentError(
          absl::StrCat("color encoding ", color.encoding(),
                       " is not COLOR_ENCODING_RGB8 or COLOR_ENCODING_GRAY8"));
  }
  const uint64_t pixels = uint64_t{color.width()} * color.height();
  if (color.data().size() != pixels * pixel_bytes) {
    return absl::InvalidArgumentError(absl::StrCat(
        "color data has ", color.data().size(), " bytes; ", color.width(), " x ", color.height(),
        " pixels of ", pixel_bytes, " bytes need ", pixels * pixel_bytes));
  }
  const auto* c = reinterpret_cast<const uint8_t*>(color.data().data());
  std::vector<uint32_t> rgb(pixels);
  for (uint64_t i = 0; i < pixels; ++i) {
    rgb[i] = pixel_bytes == 3 ? PackRgb(c[3 * i], c[3 * i + 1], c[3 * i + 2])
                              : PackRgb(c[i], c[i], c[i]);
  }
  return rgb;
}

}  // namespace cornerpose::wire
