// The pinhole camera behind a frame: recovered from an organized cloud, and
// used to project hypotheses back into the image.
#pragma once

#include <array>
#include <optional>
#include <vector>

#include "absl/status/statusor.h"
#include "common/perception/types.h"

namespace cornerpose {

// Recovers fx, fy, cx, cy from an organized cloud by least squares on
// x/z = (u - cx)/fx and y/z = (v - cy)/fy over its valid pixels. Exact for a
// cloud made by a pinhole camera; FAILED_PRECONDITION when the cloud is not
// organized or has too few valid points to fit.
absl::StatusOr<CameraIntrinsics> EstimateIntrinsics(const PointCloud& cloud);

// Pixel coordinates of a camera-frame point (z > 0 assumed).
inline Eigen::Vector2d Project(const CameraIntrinsics& k, const Eigen::Vector3d& p) {
  return {k.fx * p.x() / p.z() + k.cx, k.fy * p.y() / p.z() + k.cy};
}

// Unit-free ray direction (z = 1) through pixel (u, v).
inline Eigen::Vector3d PixelRay(const CameraIntrinsics& k, double u, double v) {
  return {(u - k.cx) / k.fx, (v - k.cy) / k.fy, 1.0};
}

// The pixel rectangle (clipped to the image) that covers the projections of
// some camera-frame points; nothing when a point is not in front of the
// camera (z <= 5 cm) or the rectangle misses the image.
struct PixelRect {
  int u0, v0, u1, v1;  // inclusive
  double area() const { return static_cast<double>(u1 - u0 + 1) * (v1 - v0 + 1); }
};
std::optional<PixelRect> ProjectedRect(const CameraIntrinsics& k,
                                       const std::vector<Eigen::Vector3d>& points);

// Where the row y crosses a convex quad (image coordinates, corners in
// order): [*x0, *x1); false when it does not.
bool QuadRowSpan(const std::array<Eigen::Vector2d, 4>& quad, double y, double* x0, double* x1);

// An organized depth image of a cloud: for an organized cloud its z values;
// for an unorganized one a z-buffer of its points projected through `k`
// (the nearest point wins a pixel). NaN where there is no return.
struct DepthImage {
  CameraIntrinsics camera;
  std::vector<float> z;  // metres, row-major
  // Brightness of the registered colour image, 0-255 per pixel, row-major;
  // empty when the frame has no colour (see PointCloud::rgb).
  std::vector<float> grey;
  bool has_grey() const { return !grey.empty(); }
  float grey_at(int u, int v) const { return grey[static_cast<size_t>(v) * camera.width + u]; }
  float at(int u, int v) const { return z[static_cast<size_t>(v) * camera.width + u]; }
  bool inside(int u, int v) const {
    return u >= 0 && v >= 0 && u < camera.width && v < camera.height;
  }
};
DepthImage MakeDepthImage(const PointCloud& cloud, const CameraIntrinsics& k);

// Median depth of the image's valid pixels (every 7th), metres; 0 when none.
// The depth the geometry rule (DeriveGeometryParameters) works at.
double MedianDepth(const DepthImage& depth);

// Projects an unorganized cloud into an organized one through `k` (nearest
// point per pixel). Organized clouds are returned unchanged.
PointCloud OrganizeByProjection(const PointCloud& cloud, const CameraIntrinsics& k);

}  // namespace cornerpose
