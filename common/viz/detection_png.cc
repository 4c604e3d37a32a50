#include "common/viz/detection_png.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "absl/strings/str_cat.h"
#include "common/io/png_io.h"
#include "common/viz/box_wireframe.h"
#include "common/viz/canvas.h"

namespace cornerpose {
namespace {

constexpr Rgb kRed = {255, 0, 0};
constexpr Rgb kBlue = {0, 90, 255};
constexpr Rgb kGreen = {0, 255, 0};
constexpr Rgb kYellow = {255, 255, 0};
constexpr Rgb kMagenta = {255, 0, 255};
// Lines are cut where they come closer to the camera plane than this.
constexpr double kNearM = 0.01;

Eigen::Vector2d Project(const CameraIntrinsics& camera, const Eigen::Vector3d& p) {
  return {camera.fx * p.x() / p.z() + camera.cx, camera.fy * p.y() / p.z() + camera.cy};
}

// Draws a 3D segment, cut to the part in front of the camera.
void Line3d(const CameraIntrinsics& camera, Eigen::Vector3d a, Eigen::Vector3d b, const Rgb& colour,
            Canvas* canvas) {
  if (!a.allFinite() || !b.allFinite()) return;
  if (a.z() < kNearM && b.z() < kNearM) return;
  if (a.z() < kNearM) a += (kNearM - a.z()) / (b.z() - a.z()) * (b - a);
  if (b.z() < kNearM) b += (kNearM - b.z()) / (a.z() - b.z()) * (a - b);
  canvas->Line(Project(camera, a), Project(camera, b), colour);
}

// Depth per pixel (NaN where nothing): the grid of a matching organized
// cloud, else a z-buffer of the projected points.
std::vector<float> DepthImage(const PointCloud& cloud, const CameraIntrinsics& camera) {
  const size_t n = static_cast<size_t>(camera.width) * camera.height;
  std::vector<float> depth(n, std::numeric_limits<float>::quiet_NaN());
  if (cloud.organized() && cloud.width == camera.width && cloud.height == camera.height) {
    for (size_t i = 0; i < n; ++i) {
      if (PointCloud::IsValid(cloud.xyz[i]) && cloud.xyz[i].z() > 0) depth[i] = cloud.xyz[i].z();
    }
    return depth;
  }
  for (const Eigen::Vector3f& p : cloud.xyz) {
    if (!p.allFinite() || p.z() <= 0) continue;
    const Eigen::Vector2d px = Project(camera, p.cast<double>());
    const double u = std::round(px.x()), v = std::round(px.y());
    if (!(u >= 0 && v >= 0 && u < camera.width && v < camera.height)) continue;
    float& d = depth[static_cast<size_t>(v) * camera.width + static_cast<size_t>(u)];
    if (std::isnan(d) || p.z() < d) d = p.z();
  }
  return depth;
}

// Grey levels from depth; the 2nd-98th percentile range maps to 255-60 so a
// few flying pixels do not wash out the contrast.
void DrawDepth(const std::vector<float>& depth, Canvas* canvas) {
  std::vector<float> valid;
  for (float z : depth) {
    if (!std::isnan(z)) valid.push_back(z);
  }
  if (valid.empty()) return;
  auto percentile = [&](double q) {
    auto it = valid.begin() + static_cast<std::ptrdiff_t>(q * (valid.size() - 1));
    std::nth_element(valid.begin(), it, valid.end());
    return *it;
  };
  const float near = percentile(0.02), far = percentile(0.98);
  const float range = std::max(far - near, 1e-3f);
  for (int v = 0; v < canvas->height(); ++v) {
    for (int u = 0; u < canvas->width(); ++u) {
      const float z = depth[static_cast<size_t>(v) * canvas->width() + u];
      if (std::isnan(z)) continue;
      const float t = std::clamp((z - near) / range, 0.0f, 1.0f);
      const auto grey = static_cast<uint8_t>(std::lround(255.0f - 195.0f * t));
      canvas->Set(u, v, {grey, grey, grey});
    }
  }
}

// The registered colour image, dimmed a little so the overlay stands out.
void DrawColour(const std::vector<uint32_t>& rgb, Canvas* canvas) {
  for (int v = 0; v < canvas->height(); ++v) {
    for (int u = 0; u < canvas->width(); ++u) {
      const uint32_t c = rgb[static_cast<size_t>(v) * canvas->width() + u];
      auto dim = [](uint32_t x) { return static_cast<uint8_t>((x & 0xFF) * 3 / 4); };
      canvas->Set(u, v, {dim(c >> 16), dim(c >> 8), dim(c)});
    }
  }
}

}  // namespace

absl::Status WriteDetectionPng(const std::string& path, const PointCloud& cloud,
                               const CameraIntrinsics& camera, const Detection& detection,
                               const BoxDims& dims) {
  if (absl::Status s = camera.Validate(); !s.ok()) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": not drawn: ", s.message()));
  }
  if (absl::Status s = cloud.Validate(); !s.ok()) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": not drawn: ", s.message()));
  }
  Canvas canvas(camera.width, camera.height);
  if (cloud.has_color() && cloud.organized() && cloud.width == camera.width &&
      cloud.height == camera.height) {
    DrawColour(cloud.rgb, &canvas);
  } else {
    DrawDepth(DepthImage(cloud, camera), &canvas);
  }

  // Boxes first, then the evidence on top: edge points, the segments fitted
  // to them, the corners.
  for (const DetectedBox& box : detection.boxes) {
    const std::array<Eigen::Vector3d, 8> corners = BoxCornersCamera(box.camera_T_box, dims);
    for (const auto& [i, j] : BoxEdges()) Line3d(camera, corners[i], corners[j], kGreen, &canvas);
  }
  for (const Eigen::Vector3f& p : detection.edge_points) {
    if (!p.allFinite() || p.z() < kNearM) continue;
    const Eigen::Vector2d px = Project(camera, p.cast<double>());
    if (px.allFinite() && std::abs(px.x()) < 1e6 && std::abs(px.y()) < 1e6) {
      canvas.Set(static_cast<int>(std::lround(px.x())), static_cast<int>(std::lround(px.y())),
                 kRed);
    }
  }
  for (const EdgeSegment& s : detection.segments) {
    Line3d(camera, s.end1.cast<double>(), s.end2.cast<double>(), kBlue, &canvas);
  }
  for (const Corner& c : detection.corners) {
    if (c.position.allFinite() && c.position.z() >= kNearM) {
      canvas.Cross(Project(camera, c.position.cast<double>()), 5, kYellow);
    }
  }
  // Box numbers last, at the grasp face centre, so they stay readable.
  for (size_t k = 0; k < detection.boxes.size(); ++k) {
    const Eigen::Vector3d& centre = detection.boxes[k].grasp_centre_camera;
    if (centre.allFinite() && centre.z() >= kNearM) {
      canvas.Number(Project(camera, centre) + Eigen::Vector2d(3, 3), static_cast<int>(k), 2,
                    kMagenta);
    }
  }
  return WriteRgbPng(path, canvas.rgb(), canvas.width(), canvas.height());
}

}  // namespace cornerpose
