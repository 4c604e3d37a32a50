#include "common/perception/seam_cues.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <vector>

#include "absl/strings/str_cat.h"

namespace cornerpose {
namespace {

// Bilinear brightness at a sub-pixel position; NaN outside the image.
float GreyAt(const DepthImage& image, double u, double v) {
  // The four pixels around (u, v) inside the image: 0 <= u < width - 1 (a
  // NaN fails it too). The truncation is then floor, without its call.
  if (!(u >= 0.0 && v >= 0.0 && u < image.camera.width - 1 && v < image.camera.height - 1)) {
    return std::numeric_limits<float>::quiet_NaN();
  }
  const int u0 = static_cast<int>(u), v0 = static_cast<int>(v);
  const double fu = u - u0, fv = v - v0;
  return static_cast<float>(
      (1 - fu) * (1 - fv) * image.grey_at(u0, v0) + fu * (1 - fv) * image.grey_at(u0 + 1, v0) +
      (1 - fu) * fv * image.grey_at(u0, v0 + 1) + fu * fv * image.grey_at(u0 + 1, v0 + 1));
}

}  // namespace

absl::Status SeamCueOptions::Validate() const {
  if (!(min_contrast > 0.0 && min_contrast <= 255.0) ||
      !(min_line_contrast >= 0.0 && min_line_contrast <= 255.0) ||
      !(texture_px >= 0.0 && texture_px <= 20.0) ||
      !(texture_ratio >= 0.0 && texture_ratio <= 10.0) ||
      !(min_coverage > 0.0 && min_coverage <= 1.0) || !(search_px >= 0.0 && search_px <= 20.0) ||
      !(flank_px >= 1.0 && flank_px <= 10.0) || !(end_margin >= 0.0 && end_margin < 0.5) ||
      !(straightness_px > 0.0 && straightness_px <= 10.0)) {
    return absl::InvalidArgumentError(absl::StrCat(
        "seam cue options out of range: min_contrast=", min_contrast,
        " (0, 255], min_line_contrast=", min_line_contrast, " [0, 255], texture_px=", texture_px,
        " [0, 20], texture_ratio=", texture_ratio, " [0, 10], min_coverage=", min_coverage,
        " (0, 1], search_px=", search_px, " [0, 20], flank_px=", flank_px, " [1, 10], end_margin=",
        end_margin, " [0, 0.5), straightness_px=", straightness_px, " (0, 10]"));
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
  // Offsets across the side, half a pixel apart: the line is sought within
  // search_px, parallel lines of a texture beyond it out to texture_px more.
  const int search_steps = static_cast<int>(std::floor(o.search_px / 0.5 + 1e-9));
  const int steps = search_steps + static_cast<int>(std::floor(o.texture_px / 0.5 + 1e-9));
  const int m = 2 * steps + 1;
  // Per sample and offset: how much darker the line is than the darker of
  // its two flanks (or the step between them, with accept_steps); NaN
  // outside the image.
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::vector<float> valley(static_cast<size_t>(n) * m, nan);
  // Per sample: where it lies and the unit direction across, in pixels.
  std::vector<Eigen::Vector2d> centre(n), unit(n);
  std::vector<char> usable(n, 0);
  double metres_per_px = 0.0;
  for (int i = 0; i < n; ++i) {
    const double t = o.end_margin + (1.0 - 2.0 * o.end_margin) * (i + 0.5) / n;
    const Eigen::Vector3d p = a + t * (b - a);
    centre[i] = Project(k, p);
    Eigen::Vector2d d = Project(k, p + 0.01 * across) - centre[i];  // 1 cm across, in pixels
    const double d_px = d.norm();
    if (!(d_px > 1e-6)) continue;
    metres_per_px = 0.01 / d_px;
    unit[i] = d / d_px;
    usable[i] = 1;
  }
  // The valleys at offsets j0..j1 (the texture band is read only when a
  // faint line asks for it).
  auto fill = [&](int j0, int j1) {
    for (int i = 0; i < n; ++i) {
      if (!usable[i]) continue;
      const Eigen::Vector2d& d = unit[i];
      for (int j = std::max(0, j0); j <= std::min(m - 1, j1); ++j) {
        const Eigen::Vector2d q = centre[i] + (j - steps) * 0.5 * d;
        const Eigen::Vector2d l = q - o.flank_px * d, r = q + o.flank_px * d;
        const float gc = GreyAt(image, q.x(), q.y());
        const float gl = GreyAt(image, l.x(), l.y());
        const float gr = GreyAt(image, r.x(), r.y());
        if (std::isnan(gc) || std::isnan(gl) || std::isnan(gr)) continue;
        const float dark = std::min(gl, gr) - gc;
        valley[static_cast<size_t>(i) * m + j] =
            o.accept_steps ? std::max(0.75f * std::abs(gl - gr), dark) : dark;
      }
    }
  };
  const int wander = static_cast<int>(std::floor(o.straightness_px / 0.5 + 1e-9));
  const int inner = search_steps + wander;  // the line and its wander
  fill(steps - inner, steps + inner);
  auto at = [&](int i, int j) { return valley[static_cast<size_t>(i) * m + j]; };
  // The line's turn against the side: where each half of the side has it
  // darkest (within straightness_px of `line`), over the distance between
  // the halves' middles.
  auto slope_at = [&](int line) -> std::optional<double> {
    double where[2];
    for (int h = 0; h < 2; ++h) {
      const int i0 = h * n / 2, i1 = (h + 1) * n / 2;
      double darkest = -std::numeric_limits<double>::infinity();
      where[h] = line;
      for (int j = std::max(0, line - wander); j <= std::min(m - 1, line + wander); ++j) {
        double sum = 0.0;
        for (int i = i0; i < i1; ++i) {
          if (!std::isnan(at(i, j))) sum += at(i, j);
        }
        if (sum > darkest) {
          darkest = sum;
          where[h] = j;
        }
      }
    }
    const double apart_m = 0.5 * (1.0 - 2.0 * o.end_margin) * (b - a).norm();
    if (!(apart_m > 0.0)) return std::nullopt;
    return (where[1] - where[0]) * 0.5 * metres_per_px / apart_m;
  };

  // A plain line: each sample's darkest offset, where it is 0.75
  // min_contrast darker than its flanks; the samples that agree with their
  // median offset within straightness_px are its coverage.
  std::vector<double> offsets;  // per sample showing a line: its offset, pixels
  offsets.reserve(n);
  for (int i = 0; i < n; ++i) {
    double best = 0.0, best_s = 0.0;
    for (int j = steps - search_steps; j <= steps + search_steps; ++j) {
      const float v = at(i, j);
      if (!std::isnan(v) && v > best) {
        best = v;
        best_s = (j - steps) * 0.5;
      }
    }
    if (best >= 0.75 * o.min_contrast) offsets.push_back(best_s);
  }
  if (!offsets.empty()) {
    std::vector<double> sorted = offsets;
    std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
    const double median = sorted[sorted.size() / 2];
    const auto straight = std::count_if(offsets.begin(), offsets.end(), [&](double s) {
      return std::abs(s - median) <= o.straightness_px;
    });
    cue.coverage = static_cast<double>(straight) / n;
    cue.offset_m = median * metres_per_px;
    cue.seam = cue.coverage >= o.min_coverage;
    if (cue.seam) cue.slope = slope_at(steps + static_cast<int>(std::lround(median / 0.5)));
  }
  if (cue.seam || o.min_line_contrast <= 0.0) return cue;

  // A faint line: the offset whose mean over the whole side is darkest (a
  // matched filter: the grain of cardboard or brick averages out, a faint
  // seam adds up). Samples out of view count as no line.
  // Offset j's valley averaged over the whole side (out of view: none), or
  // nothing when no sample has it.
  auto side_mean = [&](int j) -> std::optional<double> {
    double sum = 0.0;
    int count = 0;
    for (int i = 0; i < n; ++i) {
      if (std::isnan(at(i, j))) continue;
      sum += at(i, j);
      ++count;
    }
    if (count == 0) return std::nullopt;
    return sum / n;
  };
  int line = -1;
  double line_mean = 0.0;
  for (int j = steps - search_steps; j <= steps + search_steps; ++j) {
    const std::optional<double> mean = side_mean(j);
    if (mean && (line < 0 || *mean > line_mean)) {
      line = j;
      line_mean = *mean;
    }
  }
  if (line < 0 || line_mean < o.min_line_contrast) return cue;
  // One by one, the samples must show it too (a few dark blotches make no
  // line), within straightness_px, at half the contrast.
  int showing = 0;
  for (int i = 0; i < n; ++i) {
    for (int j = std::max(0, line - wander); j <= std::min(m - 1, line + wander); ++j) {
      if (at(i, j) >= 0.5 * o.min_line_contrast) {
        ++showing;
        break;
      }
    }
  }
  // And it must stand out from the lines parallel to it clear of its
  // flanks: wood grain and print are many lines, a seam is one.
  fill(0, steps - inner - 1);
  fill(steps + inner + 1, m - 1);
  double texture = 0.0;
  for (int j = 0; j < m; ++j) {
    if (std::abs(j - line) * 0.5 < o.flank_px + 1.5) continue;
    texture = std::max(texture, side_mean(j).value_or(0.0));
  }
  if (showing >= o.min_coverage * n && line_mean >= o.texture_ratio * texture) {
    cue.coverage = static_cast<double>(showing) / n;
    cue.offset_m = (line - steps) * 0.5 * metres_per_px;
    cue.seam = true;
    cue.slope = slope_at(line);
  }
  return cue;
}

}  // namespace cornerpose
