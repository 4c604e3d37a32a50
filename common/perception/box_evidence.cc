#include "common/perception/box_evidence.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <tuple>
#include <vector>

#include "absl/strings/str_cat.h"
#include "common/perception/box_pose.h"

namespace cornerpose {

absl::Status EvidenceOptions::Validate() const {
  if (!(depth_tolerance_base_m > 0.0 && depth_tolerance_base_m <= 0.2)) {
    return absl::InvalidArgumentError(
        absl::StrCat("depth_tolerance_base_m=", depth_tolerance_base_m, " is outside (0, 0.2] m"));
  }
  if (!(depth_tolerance_per_m2 >= 0.0 && depth_tolerance_per_m2 <= 0.2)) {
    return absl::InvalidArgumentError(absl::StrCat(
        "depth_tolerance_per_m2=", depth_tolerance_per_m2, " is outside [0, 0.2] 1/m"));
  }
  if (!(outline_margin_m >= 0.0 && outline_margin_m <= 0.1)) {
    return absl::InvalidArgumentError(
        absl::StrCat("outline_margin_m=", outline_margin_m, " is outside [0, 0.1] m"));
  }
  if (!(side_face_allowance_m >= 0.0 && side_face_allowance_m <= 0.1)) {
    return absl::InvalidArgumentError(
        absl::StrCat("side_face_allowance_m=", side_face_allowance_m, " is outside [0, 0.1] m"));
  }
  if (max_samples < 10 || max_samples > 10000000) {
    return absl::InvalidArgumentError(
        absl::StrCat("evidence max_samples=", max_samples, " is outside [10, 1e7]"));
  }
  if (gate_max_samples < 10 || gate_max_samples > 10000000) {
    return absl::InvalidArgumentError(
        absl::StrCat("evidence gate_max_samples=", gate_max_samples, " is outside [10, 1e7]"));
  }
  return absl::OkStatus();
}

namespace {

// Area of a convex quad clipped to the rectangle [x0, x1] x [y0, y1]
// (Sutherland-Hodgman, one edge of the rectangle at a time). Pixels^2.
double ClippedArea(const std::array<Eigen::Vector2d, 4>& quad, double x0, double y0, double x1,
                   double y1) {
  // Each clip by a half-plane adds at most one corner: 8 at most.
  std::array<Eigen::Vector2d, 8> poly, next;
  std::copy(quad.begin(), quad.end(), poly.begin());
  int n = 4;
  // Each clip keeps the side where s * p[axis] <= s * limit.
  const std::array<std::tuple<int, double, double>, 4> clips = {
      {{0, -1.0, x0}, {0, 1.0, x1}, {1, -1.0, y0}, {1, 1.0, y1}}};
  for (const auto& [axis, s, limit] : clips) {
    int m = 0;
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector2d& p = poly[i];
      const Eigen::Vector2d& q = poly[(i + 1) % n];
      const bool p_in = s * p[axis] <= s * limit, q_in = s * q[axis] <= s * limit;
      if (p_in) next[m++] = p;
      if (p_in != q_in) next[m++] = p + (q - p) * ((limit - p[axis]) / (q[axis] - p[axis]));
    }
    poly = next;
    n = m;
    if (n == 0) return 0.0;
  }
  double area = 0.0;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector2d& p = poly[i];
    const Eigen::Vector2d& q = poly[(i + 1) % n];
    area += p.x() * q.y() - q.x() * p.y();
  }
  return 0.5 * std::abs(area);
}

}  // namespace

BoxEvidence MeasureBox(const DepthImage& depth, const Eigen::Isometry3d& camera_T_box,
                       const BoxDims& dims, const EvidenceOptions& options) {
  BoxEvidence ev;
  const CameraIntrinsics& k = depth.camera;
  // Screen-space bounds of the box.
  const std::array<Eigen::Vector3d, 8> corners = BoxCorners(camera_T_box, dims);
  for (const Eigen::Vector3d& c : corners) {
    if (c.z() <= 0.05) {
      ev.in_front_of_camera = false;
      return ev;
    }
  }
  const std::optional<PixelRect> rect =
      ProjectedRect(k, std::vector<Eigen::Vector3d>(corners.begin(), corners.end()));
  if (!rect) return ev;
  const int ua = rect->u0, ub = rect->u1, va = rect->v0, vb = rect->v1;
  const int step = std::max(1, static_cast<int>(std::sqrt(rect->area() / options.max_samples)));

  // Ray casting in the box frame (slab method).
  const Eigen::Matrix3d box_R_camera = camera_T_box.linear().transpose();
  const Eigen::Vector3d origin = -(box_R_camera * camera_T_box.translation());
  const Eigen::Vector3d half = 0.5 * dims.vec();
  // The ray through pixel (u, v) enters the box at depth *t through face
  // *face; false when it misses.
  // The slabs' planes relative to the ray origin, per axis.
  const Eigen::Vector3d slab_lo = -half - origin, slab_hi = half - origin;
  auto cast_ray = [&](const Eigen::Vector3d& ray, double* t, int* face) {
    const Eigen::Vector3d dir = box_R_camera * ray;
    double t_near = -std::numeric_limits<double>::max(), t_far = std::numeric_limits<double>::max();
    int near_axis = -1;
    for (int a = 0; a < 3; ++a) {
      if (std::abs(dir[a]) < 1e-12) {
        if (std::abs(origin[a]) > half[a]) return false;
        continue;
      }
      const double inv = 1.0 / dir[a];
      double t1 = slab_lo[a] * inv, t2 = slab_hi[a] * inv;
      if (t1 > t2) std::swap(t1, t2);
      if (t1 > t_near) {
        t_near = t1;
        near_axis = a;
      }
      t_far = std::min(t_far, t2);
      if (t_near > t_far) return false;
    }
    if (near_axis < 0 || t_near <= 0.0) return false;
    *t = t_near;  // rays have unit z
    // The ray enters through the face on the side it comes from.
    *face = 2 * near_axis + (dir[near_axis] < 0.0 ? 0 : 1);
    return true;
  };
  auto cast = [&](double u, double v, double* t, int* face) {
    return cast_ray(PixelRay(k, u, v), t, face);
  };
  // The rays' x per column and y per row of the rectangle (PixelRay's values).
  std::vector<double> ray_x(ub - ua + 1), ray_y(vb - va + 1);
  for (int u = ua; u <= ub; ++u) ray_x[u - ua] = PixelRay(k, u, 0).x();
  for (int v = va; v <= vb; ++v) ray_y[v - va] = PixelRay(k, 0, v).y();
  // The outline margin in pixels at the box's depth.
  const double margin_px =
      options.outline_margin_m > 0.0
          ? std::max(1.0, options.outline_margin_m * k.fx / camera_T_box.translation().z())
          : 0.0;
  auto near_outline = [&](int u, int v) {
    if (margin_px <= 0.0) return false;
    double t;
    int face;
    for (const auto& [du, dv] :
         {std::pair{1.0, 0.0}, std::pair{-1.0, 0.0}, std::pair{0.0, 1.0}, std::pair{0.0, -1.0}}) {
      if (!cast(u + du * margin_px, v + dv * margin_px, &t, &face)) return true;
    }
    return false;
  };
  // The faces the camera sees, each a convex quad in the image: a pixel's
  // ray enters the box through the face whose quad holds the pixel (what
  // the slab cast gives, without casting every pixel), at the depth where
  // it meets the face's plane.
  struct VisibleFace {
    int index;
    Eigen::Vector3d normal;  // outward, camera frame
    double plane;            // normal . x on the face
    std::array<Eigen::Vector2d, 4> quad;
  };
  std::vector<VisibleFace> faces;
  const Eigen::Matrix3d& R = camera_T_box.linear();
  for (int fi = 0; fi < 6; ++fi) {
    const int n = fi / 2, a = (n + 1) % 3, b = (n + 2) % 3;
    const Eigen::Vector3d normal = (fi % 2 == 0 ? 1.0 : -1.0) * R.col(n);
    const Eigen::Vector3d centre = camera_T_box.translation() + normal * half[n];
    if (normal.dot(centre) >= 0.0) continue;  // seen from behind, or edge-on
    VisibleFace f{fi, normal, normal.dot(centre), {}};
    const double sa[4] = {-1.0, 1.0, 1.0, -1.0}, sb[4] = {-1.0, -1.0, 1.0, 1.0};
    for (int c = 0; c < 4; ++c) {
      f.quad[c] = Project(k, centre + sa[c] * half[a] * R.col(a) + sb[c] * half[b] * R.col(b));
    }
    faces.push_back(f);
  }
  // The face the box shows most (the largest area of its quad inside the
  // image, as the grasp face is the one with the most pixels): the others
  // get the side-face allowance.
  int main_face = -1;
  double main_area = -1.0;
  for (const VisibleFace& face : faces) {
    const double area =
        ClippedArea(face.quad, ua, va, ub + 1.0, vb + 1.0);  // the rectangle is inside the image
    if (area > main_area) {
      main_area = area;
      main_face = face.index;
    }
  }
  std::array<int, 6> face_px{};
  for (int v = va; v <= vb; v += step) {
    const double ray_yv = ray_y[v - va];
    for (const VisibleFace& face : faces) {
      // The quad's span on this row, [x0, x1): neighbouring faces share an
      // end, so no pixel counts twice.
      double x0, x1;
      if (!QuadRowSpan(face.quad, v, &x0, &x1)) continue;
      const int first = ua + std::max(0, static_cast<int>(std::ceil((x0 - ua) / step))) * step;
      for (int u = first; u <= ub && u < x1; u += step) {
        const double facing =
            face.normal.x() * ray_x[u - ua] + face.normal.y() * ray_yv + face.normal.z();
        if (!(facing < 0.0)) continue;
        const double z_model = face.plane / facing;  // rays have unit z
        FaceEvidence& f = ev.faces[face.index];
        ++face_px[face.index];
        const float z = depth.at(u, v);
        const double tol =
            options.depth_tolerance_base_m + options.depth_tolerance_per_m2 * z_model * z_model;
        const bool disagrees = std::isnan(z) || z > z_model + tol;
        if (disagrees && near_outline(u, v)) {
          ++f.border;
          continue;
        }
        if (face.index != main_face && z > z_model + tol &&
            z <= z_model + tol + options.side_face_allowance_m) {
          ++f.border;
          continue;
        }
        ++f.expected;
        if (std::isnan(z)) {
          ++f.missing;
        } else if (z < z_model - tol) {
          ++f.occluded;
        } else if (z > z_model + tol) {
          ++f.see_through;
        } else {
          ++f.agree;
        }
      }
    }
  }
  int best = 0;
  for (int f = 0; f < 6; ++f) {
    if (face_px[f] > face_px[best]) best = f;
    FaceEvidence& t = ev.total;
    t.expected += ev.faces[f].expected;
    t.agree += ev.faces[f].agree;
    t.occluded += ev.faces[f].occluded;
    t.see_through += ev.faces[f].see_through;
    t.missing += ev.faces[f].missing;
    t.border += ev.faces[f].border;
  }
  ev.grasp_face = static_cast<BoxFace>(best);
  return ev;
}

}  // namespace cornerpose
