#include "tests/support/kinect_noise.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "tests/support/pixel_status.h"

namespace cornerpose::testing::internal {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kDeg = std::numbers::pi / 180.0;

// Angle between a surface normal and the direction towards a viewpoint.
double Incidence(const Eigen::Vector3d& normal, const Eigen::Vector3d& to_viewer) {
  const double c = std::abs(normal.dot(to_viewer)) / to_viewer.norm();
  return std::acos(std::clamp(c, 0.0, 1.0));
}

// theta / (pi/2 - theta), capped so that near-grazing pixels stay finite.
double GrazingRatio(double theta, double cap_deg) {
  theta = std::min(theta, cap_deg * kDeg);
  return theta / (std::numbers::pi / 2 - theta);
}

void Blur1d(const std::vector<double>& in, int width, int height, bool along_x,
            const std::vector<double>& kernel, std::vector<double>* out) {
  const int r = static_cast<int>(kernel.size()) / 2;
  for (int v = 0; v < height; ++v) {
    for (int u = 0; u < width; ++u) {
      double sum = 0.0;
      for (int k = -r; k <= r; ++k) {
        const int uu = along_x ? std::clamp(u + k, 0, width - 1) : u;
        const int vv = along_x ? v : std::clamp(v + k, 0, height - 1);
        sum += kernel[k + r] * in[vv * width + uu];
      }
      (*out)[v * width + u] = sum;
    }
  }
}

}  // namespace

std::vector<double> SmoothGaussianField(int width, int height, double sigma_px, std::mt19937& rng) {
  std::normal_distribution<double> normal;
  std::vector<double> field(static_cast<size_t>(width) * height);
  for (double& x : field) x = normal(rng);
  if (sigma_px <= 0.0) return field;
  const int r = std::max(1, static_cast<int>(std::ceil(3.0 * sigma_px)));
  std::vector<double> kernel(2 * r + 1);
  for (int k = -r; k <= r; ++k) kernel[k + r] = std::exp(-0.5 * k * k / (sigma_px * sigma_px));
  std::vector<double> tmp(field.size());
  Blur1d(field, width, height, true, kernel, &tmp);
  Blur1d(tmp, width, height, false, kernel, &field);
  double mean = 0.0, sq = 0.0;
  for (double x : field) mean += x;
  mean /= field.size();
  for (double x : field) sq += (x - mean) * (x - mean);
  const double scale = 1.0 / std::sqrt(std::max(sq / field.size(), 1e-30));
  for (double& x : field) x = (x - mean) * scale;
  return field;
}

std::vector<double> ApplyKinectNoise(const RayCaster& caster, const CameraIntrinsics& camera,
                                     const NoiseOptions& noise, const std::vector<Hit>& nominal,
                                     std::mt19937& rng, RenderStats* stats) {
  const int width = camera.width;
  const int height = camera.height;
  const int n = width * height;
  std::normal_distribution<double> normal;
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::vector<uint8_t> status(n, kValid);
  std::vector<Hit> surface = nominal;
  std::vector<Eigen::Vector3d> point(n);  // where the (jittered) ray meets the surface

  // 1. Lateral noise: re-cast through jittered positions; the depth goes back
  // to the nominal pixel, which makes outlines ragged.
  std::vector<double> jitter_u, jitter_v;
  if (noise.lateral_sigma_px > 0.0) {
    jitter_u = SmoothGaussianField(width, height, noise.lateral_correlation_px, rng);
    jitter_v = SmoothGaussianField(width, height, noise.lateral_correlation_px, rng);
  }
  for (int i = 0; i < n; ++i) {
    const double u = i % width, v = i / width;
    double du = 0.0, dv = 0.0;
    if (noise.lateral_sigma_px > 0.0 && nominal[i].object != kNothing) {
      const double theta = Incidence(nominal[i].normal, -caster.Ray(u, v));
      const double sigma = noise.lateral_sigma_px + 0.035 * GrazingRatio(theta, 85.0);
      du = sigma * (normal(rng) + jitter_u[i]) / std::numbers::sqrt2;
      dv = sigma * (normal(rng) + jitter_v[i]) / std::numbers::sqrt2;
      surface[i] = caster.Cast(u + du, v + dv);
    }
    if (surface[i].object == kNothing) {
      status[i] = kNoReturn;
      continue;
    }
    point[i] = surface[i].depth * caster.Ray(u + du, v + dv);
  }

  // 2. Projector shadow: no IR pattern where the projector is hidden.
  const Eigen::Vector3d& projector = caster.projector();
  if (noise.projector_shadow) {
    for (int i = 0; i < n; ++i) {
      if (status[i] != kValid) continue;
      const Eigen::Vector3d to_projector = projector - point[i];
      if (surface[i].normal.dot(to_projector) <= 0.0 ||
          caster.ProjectorBlocked(point[i], surface[i].object)) {
        status[i] = kShadow;
      }
    }
  }

  // 3. Grazing angles: a smooth field thresholded by the dropout probability,
  // so steep faces lose coherent patches.
  if (noise.grazing_dropout) {
    const double theta_max = std::uniform_real_distribution<double>(
                                 noise.grazing_max_deg_min, noise.grazing_max_deg_max)(rng) *
                             kDeg;
    const double theta_start = noise.grazing_start_deg * kDeg;
    const std::vector<double> field =
        SmoothGaussianField(width, height, noise.grazing_correlation_px, rng);
    for (int i = 0; i < n; ++i) {
      if (status[i] != kValid) continue;
      const Eigen::Vector3d& nrm = surface[i].normal;
      const double theta =
          std::max(Incidence(nrm, -point[i]), Incidence(nrm, projector - point[i]));
      const double x = std::clamp((theta - theta_start) / (theta_max - theta_start), 0.0, 1.0);
      const double p = std::pow(x, 1.5);
      const double u01 = 0.5 * std::erfc(-field[i] / std::numbers::sqrt2);
      if (u01 < p) status[i] = kGrazing;
    }
  }

  std::vector<double> depth(n, kNaN);
  for (int i = 0; i < n; ++i) {
    if (status[i] == kValid) depth[i] = surface[i].depth;
  }

  // 4. Flying pixels between foreground and background at depth jumps.
  if (noise.flying_prob > 0.0) {
    const std::vector<double> before = depth;
    const int offsets[4][2] = {{-1, 0}, {1, 0}, {0, -1}, {0, 1}};
    for (int i = 0; i < n; ++i) {
      if (std::isnan(before[i])) continue;
      const int u = i % width, v = i / width;
      int candidates[4], count = 0;
      for (const auto& o : offsets) {
        const int uu = u + o[0], vv = v + o[1];
        if (uu < 0 || vv < 0 || uu >= width || vv >= height) continue;
        const double z_nb = before[vv * width + uu];
        if (!std::isnan(z_nb) && std::abs(z_nb - before[i]) > noise.flying_jump_m) {
          candidates[count++] = vv * width + uu;
        }
      }
      if (count == 0 || uniform(rng) >= noise.flying_prob) continue;
      const int nb = candidates[std::min(count - 1, static_cast<int>(uniform(rng) * count))];
      const double alpha = 0.15 + 0.7 * uniform(rng);
      depth[i] = before[i] + alpha * (before[nb] - before[i]);
      ++stats->flying;
    }
  }

  // 5. Axial noise in depth, then disparity quantization and mm output.
  const double fb = noise.ir_focal_px * noise.baseline_m;
  std::vector<double> axial;
  if (noise.axial_noise) {
    axial = SmoothGaussianField(width, height, noise.axial_correlation_px, rng);
  }
  for (int i = 0; i < n; ++i) {
    double z = depth[i];
    if (std::isnan(z)) continue;
    if (noise.axial_noise) {
      const double theta = Incidence(surface[i].normal, -point[i]);
      double sigma = 1.2e-3 + 1.9e-3 * (z - 0.4) * (z - 0.4);
      if (theta > 60.0 * kDeg) {
        const double r = GrazingRatio(theta, 80.0);
        sigma += 1e-4 / std::sqrt(z) * r * r;
      }
      // Quantization adds q^2/12 of variance; take it out so the total is sigma.
      double var = sigma * sigma;
      if (noise.quantize) {
        const double q = z * z * noise.disparity_step_px / fb;
        var = std::max(var - q * q / 12.0, 0.0);
      }
      z += std::sqrt(var) * (normal(rng) + axial[i]) / std::numbers::sqrt2;
    }
    if (noise.quantize && z > 0.0) {
      const double d = std::round(fb / z / noise.disparity_step_px) * noise.disparity_step_px;
      z = d > 0.0 ? fb / d : kNaN;
    }
    if (noise.output_step_m > 0.0) z = std::round(z / noise.output_step_m) * noise.output_step_m;
    depth[i] = z;
  }

  // 6. Random dropouts, small blobs, and the valid range.
  if (noise.dropout_prob > 0.0) {
    for (int i = 0; i < n; ++i) {
      if (uniform(rng) < noise.dropout_prob && status[i] == kValid) status[i] = kDropout;
    }
  }
  for (int b = 0; b < noise.num_blobs; ++b) {
    const double cu = uniform(rng) * width, cv = uniform(rng) * height;
    const double ra = 1.5 + 4.5 * uniform(rng), rb = 1.5 + 4.5 * uniform(rng);
    const double angle = uniform(rng) * std::numbers::pi;
    const double c = std::cos(angle), s = std::sin(angle);
    const int r = static_cast<int>(std::ceil(std::max(ra, rb)));
    for (int v = static_cast<int>(cv) - r; v <= static_cast<int>(cv) + r; ++v) {
      for (int u = static_cast<int>(cu) - r; u <= static_cast<int>(cu) + r; ++u) {
        if (u < 0 || v < 0 || u >= width || v >= height) continue;
        const double x = (u - cu) * c + (v - cv) * s, y = -(u - cu) * s + (v - cv) * c;
        if ((x * x) / (ra * ra) + (y * y) / (rb * rb) <= 1.0 && status[v * width + u] == kValid) {
          status[v * width + u] = kDropout;
        }
      }
    }
  }
  FinishPixels(status, noise.min_range_m, noise.max_range_m, /*output_step_m=*/0.0, depth, stats);
  return depth;
}

}  // namespace cornerpose::testing::internal
