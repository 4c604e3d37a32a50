#include "common/perception/seam_split_faces.h"

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "absl/strings/str_cat.h"
#include "common/perception/face_proposals.h"
#include "common/perception/internal/round_half_away.h"

namespace cornerpose {
namespace {

// A place a face may end along one axis of the outline: a seam or a side of
// the outline in view. Metres from the outline's corner; strength for the
// order in which faces are kept (a side of the outline counts 1).
struct Stop {
  double at;
  double strength;
};

// Two stops a side of the box apart: the face between them along one axis.
struct Span {
  double from, to;
  int dim;  // box axis the span measures
  double strength;
};

// The outline rectangle turned in its plane (within +-max_deg, in steps
// of step_deg) to where the patch's holes (no return, behind its plane by
// more than `behind`, or a thin dark line in the grey image) line up best:
// the seams of a layer run along its sides, but the outline of a layer cut
// by the image border may be the border's, off them, and a scan line then
// crosses each seam instead of running along it. The holes' coordinates on
// the plane are binned every 4 mm across both axes at each angle; the
// angle whose bins are most concentrated (sum of squared counts) wins. The
// turned rectangle covers the outline.
// A pixel of a thin dark line in the grey image (a seam the depth fills):
// darker by kContrast grey levels than the pixels kReach to either side of
// it across a row or a column. Never with no grey image.
bool DarkLine(const DepthImage& depth, int u, int v) {
  constexpr int kReach = 3;
  constexpr float kContrast = 6.0f;
  if (!depth.has_grey()) return false;
  const CameraIntrinsics& k = depth.camera;
  if (u < kReach || v < kReach || u >= k.width - kReach || v >= k.height - kReach) return false;
  const float g = depth.grey_at(u, v) + kContrast;
  return (g <= depth.grey_at(u - kReach, v) && g <= depth.grey_at(u + kReach, v)) ||
         (g <= depth.grey_at(u, v - kReach) && g <= depth.grey_at(u, v + kReach));
}

PlaneRectangle AlignedToHoles(const DepthImage& depth, const PlanarPatches& patches, int patch_id,
                              const PlaneRectangle& rect, double behind, double max_deg,
                              double step_deg) {
  if (max_deg <= 0.0 || step_deg <= 0.0) return rect;
  const CameraIntrinsics& k = depth.camera;
  // The patch's cells' bounds, in pixels.
  int c0 = patches.cells_wide, c1 = -1, r0 = patches.cells_high, r1 = -1;
  for (int r = 0; r < patches.cells_high; ++r) {
    for (int c = 0; c < patches.cells_wide; ++c) {
      if (patches.label[static_cast<size_t>(r) * patches.cells_wide + c] != patch_id) continue;
      c0 = std::min(c0, c);
      c1 = std::max(c1, c);
      r0 = std::min(r0, r);
      r1 = std::max(r1, r);
    }
  }
  if (c1 < 0) return rect;
  const int step_px = patches.step_px;
  auto in_patch = [&](int u, int v) { return patches.PatchAt(u, v) == patch_id; };
  const double n_c = rect.normal.dot(rect.centre);
  // Every other pixel of every other row: a seam's holes still line up.
  std::vector<Eigen::Vector2d> holes;
  for (int v = r0 * step_px; v < std::min(k.height, (r1 + 1) * step_px); v += 2) {
    for (int u = c0 * step_px + (v / 2) % 2; u < std::min(k.width, (c1 + 1) * step_px); u += 2) {
      const Eigen::Vector3d ray = PixelRay(k, u, v);
      const float z = depth.at(u, v);
      if (!std::isnan(z) &&
          (static_cast<double>(z) * ray - rect.centre).dot(rect.normal) >= -behind &&
          !DarkLine(depth, u, v)) {
        continue;
      }
      // On the patch, or between its cells (a seam's cells are not on it).
      const int d = 2 * step_px;
      if (!in_patch(u, v) && !(in_patch(u - d, v) && in_patch(u + d, v)) &&
          !(in_patch(u, v - d) && in_patch(u, v + d))) {
        continue;
      }
      const double nr = rect.normal.dot(ray);
      if (std::abs(nr) < 1e-6) continue;
      const Eigen::Vector3d q = (n_c / nr) * ray - rect.centre;
      holes.emplace_back(q.dot(rect.axis_u), q.dot(rect.axis_v));
    }
  }
  if (holes.size() < 25) return rect;
  constexpr double kBin = 0.004;
  const double reach = 0.5 * std::hypot(rect.width, rect.height) + kBin;
  const int bins = static_cast<int>(2.0 * reach / kBin) + 1;
  std::vector<int> hu(bins), hv(bins);
  auto score_at = [&](double deg) {
    const double th = deg * M_PI / 180.0, c = std::cos(th), s = std::sin(th);
    std::fill(hu.begin(), hu.end(), 0);
    std::fill(hv.begin(), hv.end(), 0);
    for (const Eigen::Vector2d& h : holes) {
      const int bu = static_cast<int>((c * h.x() + s * h.y() + reach) / kBin);
      const int bv = static_cast<int>((-s * h.x() + c * h.y() + reach) / kBin);
      if (bu >= 0 && bu < bins) ++hu[bu];
      if (bv >= 0 && bv < bins) ++hv[bv];
    }
    double score = 0.0;
    for (int b = 0; b < bins; ++b) score += double(hu[b]) * hu[b] + double(hv[b]) * hv[b];
    return score;
  };
  // Coarse steps of 4 fine ones over the range, then the fine steps around
  // the best; ties keep the angle nearer the outline's own.
  double best_score = -1.0, best_deg = 0.0;
  auto consider = [&](double deg) {
    const double score = score_at(deg);
    if (score > best_score || (score == best_score && std::abs(deg) < std::abs(best_deg))) {
      best_score = score;
      best_deg = deg;
    }
  };
  const double coarse = 4.0 * step_deg;
  const int coarse_steps = static_cast<int>(std::floor(max_deg / coarse));
  for (int i = -coarse_steps; i <= coarse_steps; ++i) consider(i * coarse);
  const double around = best_deg;
  for (int i = -3; i <= 3; ++i) {
    if (i != 0 && std::abs(around + i * step_deg) <= max_deg) consider(around + i * step_deg);
  }
  const double best = best_deg * M_PI / 180.0;
  if (best == 0.0) return rect;
  PlaneRectangle turned = rect;
  const double c = std::cos(best), s = std::sin(best);
  turned.axis_u = c * rect.axis_u + s * rect.axis_v;
  turned.axis_v = -s * rect.axis_u + c * rect.axis_v;
  turned.width = std::abs(c) * rect.width + std::abs(s) * rect.height;
  turned.height = std::abs(s) * rect.width + std::abs(c) * rect.height;
  return turned;
}

}  // namespace

absl::Status SeamSplitOptions::Validate() const {
  auto outside = [](const char* name, double value, const char* range) {
    return absl::InvalidArgumentError(
        absl::StrCat("faces.seam_split.", name, "=", value, " is outside ", range));
  };
  if (!(step_m > 0.0 && step_m <= 0.02)) return outside("step_m", step_m, "(0, 0.02]");
  if (!(min_seam_share > 0.0 && min_seam_share <= 1.0)) {
    return outside("min_seam_share", min_seam_share, "(0, 1]");
  }
  if (!(min_seam_ratio >= 1.0 && min_seam_ratio <= 100.0)) {
    return outside("min_seam_ratio", min_seam_ratio, "[1, 100]");
  }
  if (!(size_tolerance_m > 0.0 && size_tolerance_m <= 0.05)) {
    return outside("size_tolerance_m", size_tolerance_m, "(0, 0.05]");
  }
  if (!(max_side_m > 0.0 && max_side_m <= 100.0)) {
    return outside("max_side_m", max_side_m, "(0, 100]");
  }
  if (!(align_max_deg >= 0.0 && align_max_deg <= 45.0)) {
    return outside("align_max_deg", align_max_deg, "[0, 45]");
  }
  if (!(align_step_deg > 0.0 && align_step_deg <= 10.0)) {
    return outside("align_step_deg", align_step_deg, "(0, 10]");
  }
  if (!(colour_seam_share >= 0.0 && colour_seam_share <= 1.0)) {
    return outside("colour_seam_share", colour_seam_share, "[0, 1]");
  }
  if (!(colour_flank_m > 0.0 && colour_flank_m <= 0.05)) {
    return outside("colour_flank_m", colour_flank_m, "(0, 0.05]");
  }
  if (!(colour_min_contrast > 0.0 && colour_min_contrast <= 255.0)) {
    return outside("colour_min_contrast", colour_min_contrast, "(0, 255]");
  }
  if (max_per_patch < 1 || max_per_patch > 1000) {
    return outside("max_per_patch", max_per_patch, "[1, 1000]");
  }
  return absl::OkStatus();
}

std::vector<Eigen::Isometry3d> SeamSplitFaces(const DepthImage& depth, const PlanarPatches& patches,
                                              int patch_id, const PlaneRectangle& outline,
                                              const BoxDims& dims, const SeamSplitOptions& o) {
  std::vector<Eigen::Isometry3d> out;
  if (!o.enabled || patch_id < 0 || patch_id >= static_cast<int>(patches.patches.size())) {
    return out;
  }
  const PlanarPatch& patch = patches.patches[patch_id];
  const CameraIntrinsics& k = depth.camera;
  const double step = o.step_m;
  if (outline.width > o.max_side_m || outline.height > o.max_side_m) return out;
  // Narrower than every side of the box: no face fits.
  const double shortest = std::min({dims.l, dims.b, dims.h}) - o.size_tolerance_m;
  if (outline.width < shortest || outline.height < shortest) return out;
  // Behind the plane by more than its noise: a groove, or what a gap shows.
  const double behind = std::max(0.005, 3.0 * patch.rms_m);
  // An outline the border does not cut runs along the layer's sides.
  const PlaneRectangle rect = patch.touches_border
                                  ? AlignedToHoles(depth, patches, patch_id, outline, behind,
                                                   o.align_max_deg, o.align_step_deg)
                                  : outline;
  const Eigen::Vector3d corner =
      rect.centre - 0.5 * rect.width * rect.axis_u - 0.5 * rect.height * rect.axis_v;
  auto pixel_of = [&](const Eigen::Vector3d& p, int* u, int* v) {
    if (p.z() <= 0.05) return false;
    const Eigen::Vector2d px = Project(k, p);
    // Far outside the image (or not a number): not on it.
    if (!(std::abs(px.x()) < 1e9 && std::abs(px.y()) < 1e9)) return false;
    *u = internal::RoundHalfAway(px.x());
    *v = internal::RoundHalfAway(px.y());
    return depth.inside(*u, *v);
  };
  auto on_patch = [&](const Eigen::Vector3d& p) {
    int u, v;
    return pixel_of(p, &u, &v) && patches.PatchAt(u, v) == patch_id;
  };
  // One cell of the patch's grid on the plane: how far a seam's own cells
  // (left out of the patch by the segmentation) reach either side of it.
  const double cell_m = std::max(step, patch.centroid.z() / k.fx * patches.step_px);

  // The share of each line's samples with no return or behind the plane,
  // lines across `axis` every `step` from the corner; -1 where too few of
  // its samples lie on the patch. A sample counts where the patch is, or
  // where it is on both sides of the line (a seam's cells). With a grey
  // image, *dark gets each line's share of samples darker than the image
  // colour_flank_m to either side of the line (SeamSplitOptions::
  // colour_seam_share): a seam the depth fills (active stereo) is a dark
  // line in colour; the edge of tape or print is darker on one side only.
  auto scan = [&](const Eigen::Vector3d& axis, double length, const Eigen::Vector3d& across,
                  double span, std::vector<double>* dark) {
    const int lines = static_cast<int>(length / step);
    const int samples = static_cast<int>(span / (2.0 * step));
    std::vector<double> share(std::max(lines, 0), -1.0);
    const bool grey = dark != nullptr && depth.has_grey() && o.colour_seam_share > 0.0;
    if (dark != nullptr) dark->assign(share.size(), -1.0);
    auto grey_at = [&](const Eigen::Vector3d& p, float* g) {
      int u, v;
      if (!pixel_of(p, &u, &v)) return false;
      *g = depth.grey_at(u, v);
      return true;
    };
    for (int i = 0; i < lines; ++i) {
      const double t = (i + 0.5) * step;
      int on = 0, holes = 0, darker = 0;
      for (int j = 0; j < samples; ++j) {
        const Eigen::Vector3d p = corner + t * axis + (j + 0.5) * 2.0 * step * across;
        int u, v;
        if (!pixel_of(p, &u, &v)) continue;
        if (patches.PatchAt(u, v) != patch_id &&
            !(on_patch(p - 1.5 * cell_m * axis) && on_patch(p + 1.5 * cell_m * axis))) {
          continue;
        }
        const float z = depth.at(u, v);
        bool hole = std::isnan(z);
        if (!hole) {
          const double off = (static_cast<double>(z) * PixelRay(k, u, v) - p).dot(rect.normal);
          if (off > behind) continue;  // something in front: no say
          hole = off < -behind;
        }
        ++on;
        holes += hole;
        // The sample's own pixel (u, v); a flank read only while it can
        // still be darker than both.
        float g0 = 0.0f, g1 = 0.0f;
        if (grey) {
          const float g = depth.grey_at(u, v) + static_cast<float>(o.colour_min_contrast);
          darker += grey_at(p - o.colour_flank_m * axis, &g0) && g <= g0 &&
                    grey_at(p + o.colour_flank_m * axis, &g1) && g <= g1;
        }
      }
      if (on >= 20) {
        share[i] = static_cast<double>(holes) / on;
        if (grey) (*dark)[i] = static_cast<double>(darker) / on;
      }
    }
    return share;
  };
  // Stops along one axis: the seams, and each side of the outline whose
  // ends are in view (a side at the image border is where the view ends).
  auto stops_along = [&](const Eigen::Vector3d& axis, double length, const Eigen::Vector3d& across,
                         double span) {
    std::vector<Stop> stops;
    std::vector<double> dark;
    const std::vector<double> share = scan(axis, length, across, span, &dark);
    // The lines whose value reaches `needed` and is their neighbours' best:
    // not lower than the one before, higher than the next.
    auto peaks = [&](const std::vector<double>& value, double needed) {
      std::vector<Stop> out;
      for (size_t i = 0; i < value.size(); ++i) {
        const double x = value[i];
        if (x < needed) continue;
        if ((i > 0 && value[i - 1] > x) || (i + 1 < value.size() && value[i + 1] >= x)) continue;
        out.push_back({(i + 0.5) * step, x});
      }
      return out;
    };
    // Colour seams: lines darker than both flanks along most of their
    // length.
    stops = peaks(dark, o.colour_seam_share);
    std::vector<double> valid;
    for (double s : share) {
      if (s >= 0.0) valid.push_back(s);
    }
    if (valid.empty()) return stops;
    std::nth_element(valid.begin(), valid.begin() + valid.size() / 2, valid.end());
    const double floor = std::max(valid[valid.size() / 2], 0.01);
    const double needed = std::max(o.min_seam_share, o.min_seam_ratio * floor);
    for (const Stop& seam : peaks(share, needed)) {
      // The same seam in colour and in depth is one stop.
      if (std::none_of(stops.begin(), stops.end(),
                       [&](const Stop& c) { return std::abs(c.at - seam.at) <= 0.004; })) {
        stops.push_back(seam);
      }
    }
    constexpr double kBorderPx = 6.0;
    for (double at : {0.0, length}) {
      bool seen = true;
      // Its middle half: a side crossing the view ends where the view does.
      for (double f : {0.25, 0.5, 0.75}) {
        const Eigen::Vector3d p = corner + at * axis + f * span * across;
        if (p.z() <= 0.05) {
          seen = false;
          break;
        }
        const Eigen::Vector2d px = Project(k, p);
        seen &= px.x() >= kBorderPx && px.y() >= kBorderPx && px.x() < k.width - kBorderPx &&
                px.y() < k.height - kBorderPx;
      }
      if (seen) stops.push_back({at, 1.0});
    }
    std::sort(stops.begin(), stops.end(), [](const Stop& a, const Stop& b) { return a.at < b.at; });
    return stops;
  };
  auto spans_of = [&](const std::vector<Stop>& stops) {
    std::vector<Span> spans;
    for (size_t a = 0; a < stops.size(); ++a) {
      for (size_t b = a + 1; b < stops.size(); ++b) {
        for (int d = 0; d < 3; ++d) {
          if (std::abs(stops[b].at - stops[a].at - dims[d]) <= o.size_tolerance_m) {
            spans.push_back({stops[a].at, stops[b].at, d, stops[a].strength + stops[b].strength});
          }
        }
      }
    }
    return spans;
  };
  const std::vector<Span> spans_u =
      spans_of(stops_along(rect.axis_u, rect.width, rect.axis_v, rect.height));
  if (spans_u.empty()) return out;
  const std::vector<Span> spans_v =
      spans_of(stops_along(rect.axis_v, rect.height, rect.axis_u, rect.width));

  struct Face {
    double strength;
    Span u, v;
  };
  std::vector<Face> faces;
  for (const Span& su : spans_u) {
    for (const Span& sv : spans_v) {
      if (su.dim == sv.dim) continue;
      const Eigen::Vector3d centre =
          corner + 0.5 * (su.from + su.to) * rect.axis_u + 0.5 * (sv.from + sv.to) * rect.axis_v;
      if (!on_patch(centre)) continue;
      faces.push_back({su.strength + sv.strength, su, sv});
    }
  }
  std::stable_sort(faces.begin(), faces.end(),
                   [](const Face& a, const Face& b) { return a.strength > b.strength; });
  std::vector<Face> kept;
  for (const Face& f : faces) {
    if (static_cast<int>(kept.size()) >= o.max_per_patch) break;
    // Equal sides (a square face) frame the same face twice.
    const bool same = std::any_of(kept.begin(), kept.end(), [&](const Face& g) {
      return std::abs(g.u.from - f.u.from) < 0.01 && std::abs(g.u.to - f.u.to) < 0.01 &&
             std::abs(g.v.from - f.v.from) < 0.01 && std::abs(g.v.to - f.v.to) < 0.01 &&
             std::abs(dims[g.u.dim] - dims[f.u.dim]) < 1e-4 &&
             std::abs(dims[g.v.dim] - dims[f.v.dim]) < 1e-4;
    });
    if (!same) kept.push_back(f);
  }
  for (const Face& f : kept) {
    const Eigen::Vector3d centre =
        corner + 0.5 * (f.u.from + f.u.to) * rect.axis_u + 0.5 * (f.v.from + f.v.to) * rect.axis_v;
    const int n = 3 - f.u.dim - f.v.dim;
    out.push_back(FacePoseAt(rect, centre, FaceTiling{n, f.u.dim, f.v.dim, 1, 1}, dims));
  }
  return out;
}

}  // namespace cornerpose
