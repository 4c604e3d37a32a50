#include "common/perception/seam_cues.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "absl/strings/str_cat.h"

namespace cornerpose {
namespace {

// Bilinear brightness at a sub-pixel position; NaN outside the image.
float GreyAt(const DepthImage& image, double u, double v) {
  const int u0 = static_cast<int>(std::floor(u)), v0 = static_cast<int>(std::floor(v));
  if (u0 < 0 || v0 < 0 || u0 + 1 >= image.camera.width || v0 + 1 >= image.camera.height) {
    return std::numeric_limits<float>::quiet_NaN();
  }
  const double fu = u - u0, fv = v - v0;
  return static_cast<float>((1 - fu) * (1 - fv) * image.grey_at(u0, v0) +
                            fu * (1 - fv) * image.grey_at(u0 + 1, v0) +
                            (1 - fu) * fv * image.grey_at(u0, v0 + 1) +
                            fu * fv * image.grey_at(u0 + 1, v0 + 1));
}

}  // namespace

absl::Status SeamCueOptions::Validate() const {
  if (!(min_contrast > 0.0 && min_contrast <= 255.0) ||
      !(min_coverage > 0.0 && min_coverage <= 1.0) || !(search_px >= 0.0 && search_px <= 20.0) ||
      !(flank_px >= 1.0 && flank_px <= 10.0) || !(end_margin >= 0.0 && end_margin < 0.5) ||
      !(straightness_px > 0.0 && straightness_px <= 10.0)) {
    return absl::InvalidArgumentError(absl::StrCat(
        "seam cue options out of range: min_contrast=", min_contrast, " (0, 255], min_coverage=",
        min_coverage, " (0, 1], search_px=", search_px, " [0, 20], flank_px=", flank_px,
        " [1, 10], end_margin=", end_margin, " [0, 0.5), straightness_px=", straightness_px,
        " (0, 10]"));
  }
  return absl::OkStatus();
}

SeamCue ColourSeamAlong(const DepthImage& image, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                        const Eigen::Vector3d& across, const SeamCueOptions& o) {
  SeamCue cue;
  if (!image.has_grey() || a.z() <= 0.05 || b.z() <= 0.05) return cue;
  const CameraIntrinsics& k = image.camera;
  const double length_px = (Project(k, a) - Project(k, b)).norm();
  const int n = std::clamp(static_cast<int>(length_px / 2.0), 8, 80);
  std::vector<double> offsets;  // per sample showing a line: its offset, pixels
  offsets.reserve(n);
  double metres_per_px = 0.0;
  for (int i = 0; i < n; ++i) {
    const double t = o.end_margin + (1.0 - 2.0 * o.end_margin) * (i + 0.5) / n;
    const Eigen::Vector3d p = a + t * (b - a);
    const Eigen::Vector2d c = Project(k, p);
    Eigen::Vector2d d = Project(k, p + 0.01 * across) - c;  // 1 cm across, in pixels
    const double d_px = d.norm();
    if (!(d_px > 1e-6)) continue;
    metres_per_px = 0.01 / d_px;
    d /= d_px;
    double best = 0.0, best_s = 0.0;
    for (double s = -o.search_px; s <= o.search_px + 1e-9; s += 0.5) {
      const Eigen::Vector2d q = c + s * d;
      const Eigen::Vector2d l = q - o.flank_px * d, r = q + o.flank_px * d;
      const float gc = GreyAt(image, q.x(), q.y());
      const float gl = GreyAt(image, l.x(), l.y());
      const float gr = GreyAt(image, r.x(), r.y());
      if (std::isnan(gc) || std::isnan(gl) || std::isnan(gr)) continue;
      // A change of shade between the two sides, or a line darker than both
      // (preferred where both show, so the offset is the line's middle).
      const double valley = std::min(gl, gr) - gc;
      const double strength =
          o.accept_steps ? std::max<double>(0.75 * std::abs(gl - gr), valley) : valley;
      if (strength > best) {
        best = strength;
        best_s = s;
      }
    }
    if (best >= 0.75 * o.min_contrast) offsets.push_back(best_s);
  }
  if (offsets.empty()) return cue;
  std::vector<double> sorted = offsets;
  std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
  const double median = sorted[sorted.size() / 2];
  const auto straight = std::count_if(offsets.begin(), offsets.end(), [&](double s) {
    return std::abs(s - median) <= o.straightness_px;
  });
  cue.coverage = static_cast<double>(straight) / n;
  cue.offset_m = median * metres_per_px;
  cue.seam = cue.coverage >= o.min_coverage;
  return cue;
}

}  // namespace cornerpose
