#include "server/http/frame_encoding.h"

#include <png.h>

#include <algorithm>
#include <cmath>
#include <cstring>

namespace cornerpose::server {
namespace {

void AppendToString(png_structp png, png_bytep data, png_size_t length) {
  auto* out = static_cast<std::string*>(png_get_io_ptr(png));
  out->append(reinterpret_cast<const char*>(data), length);
}

void NoFlush(png_structp /*png*/) {}

// 8-bit RGB, row-major, to PNG bytes ("" when libpng fails).
std::string EncodeRgbPng(const std::vector<uint8_t>& rgb, int width, int height) {
  std::string out;
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  if (png == nullptr) return out;
  png_infop info = png_create_info_struct(png);
  if (info == nullptr || setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, info != nullptr ? &info : nullptr);
    return {};
  }
  png_set_write_fn(png, &out, AppendToString, NoFlush);
  // Fast over small: the view refetches the image for every frame.
  png_set_compression_level(png, 1);
  png_set_IHDR(png, info, width, height, 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  for (int v = 0; v < height; ++v) {
    png_write_row(png, const_cast<png_bytep>(rgb.data() + static_cast<size_t>(v) * width * 3));
  }
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return out;
}

// The pixel of point i: its place in an organized cloud of the camera's
// size, else its projection; false when outside the image.
bool PixelOf(const PointCloud& cloud, size_t i, const CameraIntrinsics& k, int* u, int* v) {
  if (cloud.organized() && cloud.width == k.width && cloud.height == k.height) {
    *u = static_cast<int>(i % cloud.width);
    *v = static_cast<int>(i / cloud.width);
    return true;
  }
  const Eigen::Vector3f& p = cloud.xyz[i];
  if (!(p.z() > 0)) return false;
  *u = static_cast<int>(std::lround(k.fx * p.x() / p.z() + k.cx));
  *v = static_cast<int>(std::lround(k.fy * p.y() / p.z() + k.cy));
  return *u >= 0 && *v >= 0 && *u < k.width && *v < k.height;
}

}  // namespace

CameraIntrinsics FrameImageCamera(const Frame& frame,
                                  const std::optional<CameraIntrinsics>& detector_camera) {
  if (frame.camera) return *frame.camera;
  if (detector_camera) return *detector_camera;
  CameraIntrinsics k;
  if (frame.cloud.organized()) {
    k.width = frame.cloud.width;
    k.height = frame.cloud.height;
  }
  return k;
}

std::vector<size_t> ViewCloudIndices(const PointCloud& cloud) {
  std::vector<size_t> out;
  const size_t n = cloud.xyz.size();
  for (size_t i = 0; i < n; ++i) {
    if (cloud.organized()) {
      const size_t u = i % cloud.width;
      const size_t v = i / cloud.width;
      if (u % 4 != 0 || v % 4 != 0) continue;
    } else if (i % 16 != 0) {
      continue;
    }
    if (PointCloud::IsValid(cloud.xyz[i])) out.push_back(i);
  }
  return out;
}

std::string FramePng(const Frame& frame, const CameraIntrinsics& k) {
  const PointCloud& cloud = frame.cloud;
  const bool color = !cloud.rgb.empty() && cloud.rgb.size() == cloud.xyz.size();
  // The depth range shaded: the 1st to 99th percentile of valid depths, so a
  // few stray points do not flatten the picture.
  float near = 0, far = 1;
  if (!color) {
    std::vector<float> z;
    z.reserve(cloud.xyz.size() / 4 + 1);
    for (size_t i = 0; i < cloud.xyz.size(); i += 4) {
      if (PointCloud::IsValid(cloud.xyz[i]) && cloud.xyz[i].z() > 0) z.push_back(cloud.xyz[i].z());
    }
    if (!z.empty()) {
      std::sort(z.begin(), z.end());
      near = z[z.size() / 100];
      far = z[z.size() - 1 - z.size() / 100];
      if (!(far > near)) far = near + 1e-3f;
    }
  }
  std::vector<uint8_t> rgb(static_cast<size_t>(k.width) * k.height * 3, 0);
  for (size_t i = 0; i < cloud.xyz.size(); ++i) {
    int u = 0, v = 0;
    if (!PixelOf(cloud, i, k, &u, &v)) continue;
    uint8_t* px = &rgb[(static_cast<size_t>(v) * k.width + u) * 3];
    if (color) {
      const uint32_t c = cloud.rgb[i];
      px[0] = (c >> 16) & 0xff;
      px[1] = (c >> 8) & 0xff;
      px[2] = c & 0xff;
      continue;
    }
    const Eigen::Vector3f& p = cloud.xyz[i];
    if (!PointCloud::IsValid(p) || !(p.z() > 0)) continue;
    const float t = std::clamp((far - p.z()) / (far - near), 0.0f, 1.0f);
    const auto g = static_cast<uint8_t>(40 + 215 * t);  // no return stays black
    px[0] = px[1] = px[2] = g;
  }
  return EncodeRgbPng(rgb, k.width, k.height);
}

std::string FrameCloudBin(const Frame& frame) {
  const PointCloud& cloud = frame.cloud;
  const std::vector<size_t> indices = ViewCloudIndices(cloud);
  const bool color = !cloud.rgb.empty() && cloud.rgb.size() == cloud.xyz.size();
  const auto count = static_cast<uint32_t>(indices.size());
  const uint32_t flags = color ? 1u : 0u;
  std::string out;
  out.reserve(12 + indices.size() * (color ? 15 : 12));
  out.append("CPC1");
  // x86 and ARM are little-endian, as the format is.
  out.append(reinterpret_cast<const char*>(&count), 4);
  out.append(reinterpret_cast<const char*>(&flags), 4);
  for (size_t i : indices) out.append(reinterpret_cast<const char*>(cloud.xyz[i].data()), 12);
  if (color) {
    for (size_t i : indices) {
      const uint32_t c = cloud.rgb[i];
      const char bytes[3] = {static_cast<char>((c >> 16) & 0xff), static_cast<char>((c >> 8) & 0xff),
                             static_cast<char>(c & 0xff)};
      out.append(bytes, 3);
    }
  }
  return out;
}

}  // namespace cornerpose::server
