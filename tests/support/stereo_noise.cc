#include "tests/support/stereo_noise.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "tests/support/kinect_noise.h"
#include "tests/support/pixel_status.h"

namespace cornerpose::testing::internal {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kDeg = std::numbers::pi / 180.0;

// The second camera's (or the projector's) shadow.
constexpr PixelStatus kOccluded = kShadow;

void Filter1d(std::vector<double>* values, int width, int height, int r, bool along_x,
              bool take_min) {
  if (r <= 0) return;
  const std::vector<double> in = *values;
  const int n_outer = along_x ? height : width, n_inner = along_x ? width : height;
  for (int o = 0; o < n_outer; ++o) {
    for (int k = 0; k < n_inner; ++k) {
      double best = in[along_x ? o * width + k : k * width + o];
      for (int j = std::max(0, k - r); j <= std::min(n_inner - 1, k + r); ++j) {
        const double x = in[along_x ? o * width + j : j * width + o];
        best = take_min ? std::min(best, x) : std::max(best, x);
      }
      (*values)[along_x ? o * width + k : k * width + o] = best;
    }
  }
}

}  // namespace

void MinFilter1d(std::vector<double>* values, int width, int height, int r, bool along_x) {
  Filter1d(values, width, height, r, along_x, true);
}
void MaxFilter1d(std::vector<double>* values, int width, int height, int r, bool along_x) {
  Filter1d(values, width, height, r, along_x, false);
}

std::vector<double> ApplyStereoNoise(const RayCaster& caster, const SurfaceTexture& texture,
                                     const CameraIntrinsics& camera, const StereoOptions& options,
                                     const std::vector<Hit>& nominal, std::mt19937& rng,
                                     RenderStats* stats) {
  const int width = camera.width, height = camera.height, n = width * height;
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::vector<uint8_t> status(n, kValid);
  std::vector<double> depth(n);
  for (int i = 0; i < n; ++i) depth[i] = nominal[i].object == kNothing ? kInf : nominal[i].depth;

  // 1. Thin gaps: a grey-scale opening (min, then max) along rows and then
  // columns takes out cracks up to gap_fill_px wide, as the matching window
  // smooths over them: seams between touching boxes vanish from the depth.
  std::vector<double> filled = depth;
  const int r_gap = (options.gap_fill_px + 1) / 2;
  for (bool along_x : {true, false}) {
    MinFilter1d(&filled, width, height, r_gap, along_x);
    MaxFilter1d(&filled, width, height, r_gap, along_x);
  }
  const std::vector<double> depth_nominal_filled = filled;
  // 2. Edge fattening: the nearer side of every jump grows by fattening_px.
  std::vector<double> fat = filled;
  MinFilter1d(&fat, width, height, options.fattening_px, true);
  MinFilter1d(&fat, width, height, options.fattening_px, false);
  std::vector<bool> moved(n, false);  // depth no longer of the nominal surface
  for (int i = 0; i < n; ++i) {
    if (fat[i] < filled[i] - options.jump_m) filled[i] = fat[i];
    moved[i] = std::abs(filled[i] - depth[i]) > 1e-6;
  }
  depth = filled;
  for (int i = 0; i < n; ++i) {
    if (!std::isfinite(depth[i])) status[i] = kNoReturn;
  }

  // 3. Flying pixels between the two sides of a jump.
  if (options.flying_prob > 0.0) {
    const std::vector<double> before = depth;
    const int offsets[4][2] = {{-1, 0}, {1, 0}, {0, -1}, {0, 1}};
    for (int i = 0; i < n; ++i) {
      if (status[i] != kValid) continue;
      const int u = i % width, v = i / width;
      int candidates[4], count = 0;
      for (const auto& o : offsets) {
        const int uu = u + o[0], vv = v + o[1];
        if (uu < 0 || vv < 0 || uu >= width || vv >= height) continue;
        const double z_nb = before[vv * width + uu];
        if (std::isfinite(z_nb) && std::abs(z_nb - before[i]) > options.jump_m) {
          candidates[count++] = vv * width + uu;
        }
      }
      if (count == 0 || uniform(rng) >= options.flying_prob) continue;
      const int nb = candidates[std::min(count - 1, static_cast<int>(uniform(rng) * count))];
      depth[i] = before[i] + (0.15 + 0.7 * uniform(rng)) * (before[nb] - before[i]);
      moved[i] = true;
      ++stats->flying;
    }
  }

  // 4. No match where the right imager cannot see the surface: behind a
  // nearer surface, or outside its image; widened towards the occluded side
  // by the matching window (a ragged margin). Filled cracks are matched.
  const double fb = camera.fx * options.baseline_m;
  std::vector<bool> gap_filled(n);
  for (int i = 0; i < n; ++i) {
    gap_filled[i] = std::isfinite(depth_nominal_filled[i]) &&
                    depth_nominal_filled[i] < nominal[i].depth - options.jump_m;
  }
  for (int i = 0; i < n; ++i) {
    if (status[i] != kValid) continue;
    const int u = i % width, v = i / width;
    if (u - fb / depth[i] < 0.0) {
      status[i] = kOccluded;
    } else if (!gap_filled[i] && nominal[i].object != kNothing &&
               caster.ProjectorBlocked(nominal[i].depth * caster.Ray(u, v), nominal[i].object)) {
      status[i] = kOccluded;
    }
  }
  if (options.occlusion_margin_px > 0) {
    const std::vector<double> ragged = SmoothGaussianField(width, height, 2.0, rng);
    const std::vector<uint8_t> before = status;
    for (int v = 0; v < height; ++v) {
      for (int u = 0; u < width; ++u) {
        const int i = v * width + u;
        if (before[i] != kValid) continue;
        // A background pixel just left of an occluded run, within the margin.
        const int margin =
            std::max<int>(0, std::lround(options.occlusion_margin_px + 1.5 * ragged[i]));
        for (int k = 1; k <= margin && u + k < width; ++k) {
          if (before[i + k] == kOccluded) {
            status[i] = kOccluded;
            break;
          }
          if (before[i + k] != kValid) break;
        }
      }
    }
  }

  // 5. Disparity noise, correlated over the matching window.
  const std::vector<double> window =
      SmoothGaussianField(width, height, options.window_correlation_px, rng);
  const std::vector<double> blob =
      SmoothGaussianField(width, height, options.blob_correlation_px, rng);
  std::normal_distribution<double> normal;
  const double w_white = std::sqrt(options.white_share), w_window = std::sqrt(options.window_share);
  const double w_blob = std::sqrt(std::max(0.0, 1.0 - options.white_share - options.window_share));
  for (int i = 0; i < n; ++i) {
    if (status[i] != kValid) continue;
    const int u = i % width, v = i / width;
    const Eigen::Vector3d ray = caster.Ray(u, v);
    const double cos_t = std::abs(nominal[i].normal.dot(ray.normalized()));
    if (!moved[i] && cos_t < std::cos(options.grazing_max_deg * kDeg)) {
      status[i] = kGrazing;
      continue;
    }
    const double sigma_d = options.subpixel_px / std::sqrt(std::max(cos_t, 0.1));
    const double field = w_white * normal(rng) + w_window * window[i] + w_blob * blob[i];
    const double d = fb / depth[i] + sigma_d * field;
    depth[i] = d > 0.0 ? fb / d : kNaN;
    if (!std::isfinite(depth[i])) status[i] = kNoReturn;
  }

  // 6. Speckle holes where the projected texture is weak, then the camera's
  // own filling of small holes from their neighbours.
  const std::vector<double> patches = SmoothGaussianField(width, height, 1.0, rng);
  for (int i = 0; i < n; ++i) {
    if (status[i] != kValid) continue;
    const int u = i % width, v = i / width;
    const double luma = texture.Luma(nominal[i], nominal[i].depth * caster.Ray(u, v));
    const double dark = std::max(0.0, 1.0 - luma / options.dark_albedo);
    const double p = options.speckle_prob + options.dark_hole_prob * dark * dark;
    if (0.5 * std::erfc(-patches[i] / std::numbers::sqrt2) < p) status[i] = kDropout;
  }
  if (options.hole_fill_px > 0) {
    for (int v = 0; v < height; ++v) {
      int u = 0;
      while (u < width) {
        const int i = v * width + u;
        if (status[i] == kValid) {
          ++u;
          continue;
        }
        int end = u;
        while (end < width && status[v * width + end] != kValid) ++end;
        const int len = end - u;
        if (u > 0 && end < width && len <= options.hole_fill_px) {
          const double za = depth[v * width + u - 1], zb = depth[v * width + end];
          if (std::abs(za - zb) < options.jump_m) {
            for (int k = u; k < end; ++k) {
              depth[v * width + k] = za + (zb - za) * (k - u + 1) / (len + 1);
              status[v * width + k] = kValid;
              moved[v * width + k] = true;
            }
          }
        }
        u = end;
      }
    }
  }

  // 7. Working range and output units; gaps filled from their sides (valid,
  // in range, moved off the nominal depth by a jump) are counted first.
  for (int i = 0; i < n; ++i) {
    if (status[i] == kValid && depth[i] >= options.min_range_m && depth[i] <= options.max_range_m &&
        moved[i] && std::isfinite(nominal[i].depth) &&
        std::abs(depth[i] - nominal[i].depth) > options.jump_m) {
      ++stats->filled;
    }
  }
  FinishPixels(status, options.min_range_m, options.max_range_m, options.output_step_m, depth,
               stats);
  return depth;
}

}  // namespace cornerpose::testing::internal
