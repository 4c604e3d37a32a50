#include "common/perception/camera_model.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "absl/strings/str_cat.h"

namespace cornerpose {
namespace {

// Fits s = (i - c)/f, i.e. i = f*s + c, by least squares.
bool FitLine(double n, double s, double ss, double i, double si, double* f, double* c) {
  const double det = n * ss - s * s;
  if (n < 100 || std::abs(det) < 1e-12 * n * n) return false;
  *f = (n * si - s * i) / det;
  *c = (i - *f * s) / n;
  return std::isfinite(*f) && *f > 0.0;
}

}  // namespace

absl::StatusOr<CameraIntrinsics> EstimateIntrinsics(const PointCloud& cloud) {
  if (!cloud.organized()) {
    return absl::FailedPreconditionError("intrinsics can only be recovered from organized clouds");
  }
  // Sums for u ~ fx*(x/z) + cx and v ~ fy*(y/z) + cy over a sparse grid.
  double n = 0, sx = 0, sxx = 0, su = 0, sxu = 0, sy = 0, syy = 0, sv = 0, syv = 0;
  const int step = std::max(1, static_cast<int>(std::sqrt(cloud.size() / 20000.0)));
  for (int v = 0; v < cloud.height; v += step) {
    for (int u = 0; u < cloud.width; u += step) {
      const Eigen::Vector3f& p = cloud.xyz[static_cast<size_t>(v) * cloud.width + u];
      if (!PointCloud::IsValid(p) || p.z() <= 0.0f) continue;
      const double a = p.x() / p.z(), b = p.y() / p.z();
      n += 1;
      sx += a, sxx += a * a, su += u, sxu += a * u;
      sy += b, syy += b * b, sv += v, syv += b * v;
    }
  }
  CameraIntrinsics k;
  k.width = cloud.width;
  k.height = cloud.height;
  if (!FitLine(n, sx, sxx, su, sxu, &k.fx, &k.cx) || !FitLine(n, sy, syy, sv, syv, &k.fy, &k.cy)) {
    return absl::FailedPreconditionError(
        absl::StrCat("too few valid points (", n, ") to recover the camera intrinsics"));
  }
  return k;
}

std::optional<PixelRect> ProjectedRect(const CameraIntrinsics& k,
                                       const std::vector<Eigen::Vector3d>& points) {
  double u0 = std::numeric_limits<double>::max(), v0 = u0, u1 = -u0, v1 = -u0;
  for (const Eigen::Vector3d& p : points) {
    if (p.z() <= 0.05) return std::nullopt;
    const Eigen::Vector2d px = Project(k, p);
    u0 = std::min(u0, px.x()), u1 = std::max(u1, px.x());
    v0 = std::min(v0, px.y()), v1 = std::max(v1, px.y());
  }
  PixelRect r{std::max(0, static_cast<int>(std::floor(u0))),
              std::max(0, static_cast<int>(std::floor(v0))),
              std::min(k.width - 1, static_cast<int>(std::ceil(u1))),
              std::min(k.height - 1, static_cast<int>(std::ceil(v1)))};
  if (r.u0 > r.u1 || r.v0 > r.v1) return std::nullopt;
  return r;
}

bool QuadRowSpan(const std::array<Eigen::Vector2d, 4>& quad, double y, double* x0, double* x1) {
  *x0 = std::numeric_limits<double>::max();
  *x1 = -std::numeric_limits<double>::max();
  for (int c = 0; c < 4; ++c) {
    const Eigen::Vector2d& p = quad[c];
    const Eigen::Vector2d& q = quad[(c + 1) % 4];
    if ((p.y() > y) == (q.y() > y)) continue;  // the edge does not cross the row
    const double x = p.x() + (y - p.y()) * (q.x() - p.x()) / (q.y() - p.y());
    *x0 = std::min(*x0, x);
    *x1 = std::max(*x1, x);
  }
  return *x0 < *x1;
}

double MedianDepth(const DepthImage& depth) {
  const std::vector<float>& z = depth.z;
  std::vector<float> valid;
  for (size_t i = 0; i < z.size(); i += 7) {
    if (std::isfinite(z[i]) && z[i] > 0.0f) valid.push_back(z[i]);
  }
  if (valid.empty()) return 0.0;
  std::nth_element(valid.begin(), valid.begin() + valid.size() / 2, valid.end());
  return valid[valid.size() / 2];
}

DepthImage MakeDepthImage(const PointCloud& cloud, const CameraIntrinsics& k) {
  DepthImage image;
  image.camera = k;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  if (cloud.organized() && cloud.width == k.width && cloud.height == k.height) {
    image.z.resize(cloud.size());
    for (size_t i = 0; i < cloud.size(); ++i) {
      image.z[i] = PointCloud::IsValid(cloud.xyz[i]) ? cloud.xyz[i].z() : nan;
    }
    if (cloud.has_color()) {
      image.grey.resize(cloud.size());
      for (size_t i = 0; i < cloud.size(); ++i) {
        const uint32_t c = cloud.rgb[i];
        image.grey[i] =
            static_cast<float>(((c >> 16) & 0xFF) + ((c >> 8) & 0xFF) + (c & 0xFF)) / 3.0f;
      }
    }
    return image;
  }
  image.z.assign(static_cast<size_t>(k.width) * k.height, nan);
  for (const Eigen::Vector3f& p : cloud.xyz) {
    if (!PointCloud::IsValid(p) || p.z() <= 0.0f) continue;
    const Eigen::Vector2d px = Project(k, p.cast<double>());
    const int u = static_cast<int>(std::lround(px.x())), v = static_cast<int>(std::lround(px.y()));
    if (!image.inside(u, v)) continue;
    float& z = image.z[static_cast<size_t>(v) * k.width + u];
    if (std::isnan(z) || p.z() < z) z = p.z();
  }
  return image;
}

PointCloud OrganizeByProjection(const PointCloud& cloud, const CameraIntrinsics& k) {
  if (cloud.organized()) return cloud;
  PointCloud out;
  out.width = k.width;
  out.height = k.height;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  out.xyz.assign(static_cast<size_t>(k.width) * k.height, Eigen::Vector3f(nan, nan, nan));
  if (cloud.has_color()) out.rgb.assign(out.xyz.size(), 0);
  for (size_t i = 0; i < cloud.xyz.size(); ++i) {
    const Eigen::Vector3f& p = cloud.xyz[i];
    if (!PointCloud::IsValid(p) || p.z() <= 0.0f) continue;
    const Eigen::Vector2d px = Project(k, p.cast<double>());
    const int u = static_cast<int>(std::lround(px.x())), v = static_cast<int>(std::lround(px.y()));
    if (u < 0 || v < 0 || u >= k.width || v >= k.height) continue;
    Eigen::Vector3f& slot = out.xyz[static_cast<size_t>(v) * k.width + u];
    if (!PointCloud::IsValid(slot) || p.z() < slot.z()) {
      slot = p;
      if (cloud.has_color()) out.rgb[static_cast<size_t>(v) * k.width + u] = cloud.rgb[i];
    }
  }
  return out;
}

}  // namespace cornerpose
