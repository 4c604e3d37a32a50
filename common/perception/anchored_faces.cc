#include "common/perception/anchored_faces.h"

#include <algorithm>
#include <cmath>

#include "absl/strings/str_cat.h"
#include "common/perception/face_proposals.h"
#include "common/perception/internal/summed_area.h"

namespace cornerpose {
namespace {

struct Anchored {
  double score;
  int shape;
  double cu, cv;  // tile centre, metres from the grid origin
};

}  // namespace

absl::Status AnchoredFaceOptions::Validate() const {
  for (const auto& [name, value] :
       {std::pair{"min_inside", min_inside}, std::pair{"min_edge", min_edge},
        std::pair{"max_beyond", max_beyond}}) {
    if (!(value >= 0.0 && value <= 1.0)) {
      return absl::InvalidArgumentError(
          absl::StrCat("faces.anchored.", name, "=", value, " is outside [0, 1]"));
    }
  }
  if (max_faces < 1 || max_faces > 1000) {
    return absl::InvalidArgumentError(
        absl::StrCat("faces.anchored.max_faces=", max_faces, " is outside [1, 1000]"));
  }
  if (max_per_patch < 1 || max_per_patch > 1000) {
    return absl::InvalidArgumentError(
        absl::StrCat("faces.anchored.max_per_patch=", max_per_patch, " is outside [1, 1000]"));
  }
  return absl::OkStatus();
}

std::vector<Eigen::Isometry3d> AnchoredFaces(const PlanarPatch& patch, const PlaneRectangle& rect,
                                             double cell_m, const CameraIntrinsics& camera,
                                             const BoxDims& dims, const AnchoredFaceOptions& o) {
  std::vector<Eigen::Isometry3d> out;
  if (!o.enabled || !(cell_m > 1e-4) || patch.points.empty()) return out;
  const double largest_face = std::max({dims.l * dims.b, dims.l * dims.h, dims.b * dims.h});
  if (rect.width * rect.height > o.max_faces * largest_face) return out;
  // The raster: the outline rectangle and a margin of kMargin cells, one
  // cell per point spacing (bounded: a patch this big is already refused).
  constexpr int kMargin = 3, kBeyond = 2;
  const double r = cell_m;
  const int w = static_cast<int>(std::ceil(rect.width / r)) + 2 * kMargin;
  const int h = static_cast<int>(std::ceil(rect.height / r)) + 2 * kMargin;
  if (w <= 2 * kMargin || h <= 2 * kMargin || static_cast<long>(w) * h > 4'000'000) return out;
  const Eigen::Vector3d origin = rect.centre - (0.5 * rect.width + kMargin * r) * rect.axis_u -
                                 (0.5 * rect.height + kMargin * r) * rect.axis_v;
  std::vector<uint8_t> hit(static_cast<size_t>(w) * h, 0);
  for (const Eigen::Vector3d& p : patch.points) {
    const Eigen::Vector3d d = p - origin;
    const int i = static_cast<int>(std::floor(d.dot(rect.axis_u) / r));
    const int j = static_cast<int>(std::floor(d.dot(rect.axis_v) / r));
    if (i >= 0 && j >= 0 && i < w && j < h) hit[static_cast<size_t>(j) * w + i] = 1;
  }
  // A closing (3 x 3 dilation, then erosion) fills the holes a tilted
  // plane's uneven point spacing leaves, without growing the outline.
  auto morph = [&](const std::vector<uint8_t>& in, bool dilate) {
    std::vector<uint8_t> res(in.size(), 0);
    for (int j = 0; j < h; ++j) {
      for (int i = 0; i < w; ++i) {
        bool any = false, all = true;
        for (int dj = -1; dj <= 1; ++dj) {
          for (int di = -1; di <= 1; ++di) {
            const int x = i + di, y = j + dj;
            const bool set =
                x >= 0 && y >= 0 && x < w && y < h && in[static_cast<size_t>(y) * w + x];
            any |= set;
            all &= set;
          }
        }
        res[static_cast<size_t>(j) * w + i] = dilate ? any : all;
      }
    }
    return res;
  };
  const std::vector<uint8_t> on = morph(morph(hit, true), false);
  // Cells whose centre the camera does not see (outside the image, or at
  // its border): nothing can be said about the patch's end there.
  std::vector<uint8_t> unseen(on.size(), 0);
  const double border_px = 4.0;
  for (int j = 0; j < h; ++j) {
    for (int i = 0; i < w; ++i) {
      const Eigen::Vector3d c = origin + (i + 0.5) * r * rect.axis_u + (j + 0.5) * r * rect.axis_v;
      bool seen = c.z() > 0.05;
      if (seen) {
        const Eigen::Vector2d px = Project(camera, c);
        seen = px.x() >= border_px && px.y() >= border_px && px.x() < camera.width - border_px &&
               px.y() < camera.height - border_px;
      }
      unseen[static_cast<size_t>(j) * w + i] = !seen;
    }
  }
  const internal::SummedArea<int> on_sum(on, w, h), unseen_sum(unseen, w, h);

  // The faces of the box, each size once: (normal axis, axis along u, along v).
  struct Shape {
    int n, su, sv, a, b;  // a x b cells
  };
  std::vector<Shape> shapes;
  for (int n = 0; n < 3; ++n) {
    const int p = (n + 1) % 3, q = (n + 2) % 3;
    for (const auto& [su, sv] : {std::pair{p, q}, std::pair{q, p}}) {
      const int a = static_cast<int>(std::lround(dims[su] / r));
      const int b = static_cast<int>(std::lround(dims[sv] / r));
      if (a < 3 || b < 3 || a > w - 2 * kMargin + 2 || b > h - 2 * kMargin + 2) continue;
      const bool repeat = std::any_of(shapes.begin(), shapes.end(), [&](const Shape& s) {
        return s.a == a && s.b == b && std::abs(dims[s.n] - dims[n]) < 1e-4;
      });
      if (!repeat) shapes.push_back({n, su, sv, a, b});
    }
  }

  std::vector<Anchored> found;
  for (size_t s = 0; s < shapes.size(); ++s) {
    const int a = shapes[s].a, b = shapes[s].b;
    for (int du : {-1, 1}) {
      for (int dv : {-1, 1}) {
        for (int j0 = 0; j0 + b <= h; ++j0) {
          for (int i0 = 0; i0 + a <= w; ++i0) {
            const int i1 = i0 + a, j1 = j0 + b;
            const double inside = on_sum.Sum(i0, j0, i1, j1) / static_cast<double>(a * b);
            if (inside < o.min_inside) continue;
            // The anchored side across u (at i1 when du = 1, at i0 when -1),
            // its inner edge and what lies beyond, over the half of it at the
            // anchored corner (the far end may be eroded or hidden); then the
            // side across v.
            const int ui = du > 0 ? i1 - kBeyond : i0, ub = du > 0 ? i1 : i0 - kBeyond;
            const int vj = dv > 0 ? j1 - kBeyond : j0, vb = dv > 0 ? j1 : j0 - kBeyond;
            const int hj0 = dv > 0 ? j1 - b / 2 : j0, hj1 = dv > 0 ? j1 : j0 + b / 2;
            const int hi0 = du > 0 ? i1 - a / 2 : i0, hi1 = du > 0 ? i1 : i0 + a / 2;
            const double side_u = kBeyond * (hj1 - hj0), side_v = kBeyond * (hi1 - hi0);
            const double edge_u = on_sum.Sum(ui, hj0, ui + kBeyond, hj1) / side_u;
            const double edge_v = on_sum.Sum(hi0, vj, hi1, vj + kBeyond) / side_v;
            if (edge_u < o.min_edge || edge_v < o.min_edge) continue;
            const double beyond_u = on_sum.Sum(ub, hj0, ub + kBeyond, hj1) / side_u;
            const double beyond_v = on_sum.Sum(hi0, vb, hi1, vb + kBeyond) / side_v;
            if (beyond_u > o.max_beyond || beyond_v > o.max_beyond) continue;
            if (unseen_sum.Sum(ub, hj0, ub + kBeyond, hj1) > 0 ||
                unseen_sum.Sum(hi0, vb, hi1, vb + kBeyond) > 0) {
              continue;
            }
            found.push_back({inside + 0.5 * (edge_u + edge_v) - beyond_u - beyond_v,
                             static_cast<int>(s), (i0 + 0.5 * a) * r, (j0 + 0.5 * b) * r});
          }
        }
      }
    }
  }
  // Best first; one face per spot and shape (neighbouring cells anchor the
  // same corner).
  std::stable_sort(found.begin(), found.end(),
                   [](const Anchored& x, const Anchored& y) { return x.score > y.score; });
  std::vector<Anchored> kept;
  for (const Anchored& f : found) {
    if (static_cast<int>(kept.size()) >= o.max_per_patch) break;
    const bool near = std::any_of(kept.begin(), kept.end(), [&](const Anchored& k) {
      return k.shape == f.shape && std::hypot(k.cu - f.cu, k.cv - f.cv) < 4.0 * r;
    });
    if (!near) kept.push_back(f);
  }
  for (const Anchored& k : kept) {
    const Shape& s = shapes[k.shape];
    out.push_back(FacePoseAt(rect, origin + k.cu * rect.axis_u + k.cv * rect.axis_v,
                             FaceTiling{s.n, s.su, s.sv, 1, 1}, dims));
  }
  return out;
}

}  // namespace cornerpose
