#include "tests/support/color_render.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

namespace cornerpose::testing::internal {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

// Directions within angular radius `radius` around dir, on a fixed spiral.
std::vector<Eigen::Vector3d> LightSamples(const Eigen::Vector3d& dir, double radius, int count) {
  const Eigen::Vector3d a = dir.unitOrthogonal(), b = dir.cross(a);
  std::vector<Eigen::Vector3d> out;
  for (int k = 0; k < count; ++k) {
    const double r = count == 1 ? 0.0 : radius * std::sqrt((k + 0.5) / count);
    const double phi = k * 2.399963;  // golden angle
    out.push_back((dir + std::tan(r) * (std::cos(phi) * a + std::sin(phi) * b)).normalized());
  }
  return out;
}

}  // namespace

uint32_t PackColor(const Eigen::Vector3d& linear) {
  uint32_t packed = 0;
  for (int c = 0; c < 3; ++c) {
    const double x = std::clamp(linear[c], 0.0, 1.0);
    const double srgb = x <= 0.0031308 ? 12.92 * x : 1.055 * std::pow(x, 1 / 2.4) - 0.055;
    packed = (packed << 8) | static_cast<uint32_t>(std::lround(255.0 * srgb));
  }
  return packed;
}

std::vector<uint32_t> RenderColor(const Scene& scene, const RayCaster& caster,
                                  const SurfaceTexture& texture, const std::vector<Hit>& nominal,
                                  const ColorOptions& options, uint32_t seed) {
  const CameraIntrinsics& cam = scene.camera;
  const int width = cam.width, height = cam.height;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::normal_distribution<double> normal;
  // The light: from above, at a random azimuth, in the camera frame.
  const double elevation =
      (options.light_elevation_min_deg +
       (options.light_elevation_max_deg - options.light_elevation_min_deg) * uniform(rng)) *
      kDeg;
  const double azimuth = 2 * std::numbers::pi * uniform(rng);
  const Eigen::Vector3d light_world(std::cos(elevation) * std::cos(azimuth),
                                    std::cos(elevation) * std::sin(azimuth), std::sin(elevation));
  const Eigen::Vector3d light = scene.world_T_camera.linear().transpose() * light_world;
  const std::vector<Eigen::Vector3d> samples =
      LightSamples(light, options.light_size_deg * kDeg, options.shadow_samples);
  const double exposure = 1.15 * (0.8 + 0.4 * uniform(rng));

  auto shade = [&](const Hit& hit, double u, double v) -> Eigen::Vector3d {
    if (hit.object == kNothing) return Eigen::Vector3d::Constant(0.02);
    const Eigen::Vector3d p = hit.depth * caster.Ray(u, v);
    const Eigen::Vector3d albedo = texture.Albedo(hit, p);
    // A surface turned away from the camera's side of the light gets only ambient.
    double direct = 0.0;
    const double cos_l = hit.normal.dot(light);
    if (cos_l > 0.0) {
      int lit = 0;
      const Eigen::Vector3d origin = p + 1e-4 * hit.normal;
      for (const Eigen::Vector3d& s : samples) lit += !caster.Occluded(origin, s, 5.0);
      direct = cos_l * lit / static_cast<double>(samples.size());
    }
    return albedo * (options.ambient + (1.0 - options.ambient) * 1.4 * direct);
  };

  // Supersample (3 x 3) where the surface under the pixel changes, so thin
  // gaps and seams blend into their pixels instead of aliasing.
  std::vector<uint32_t> rgb(static_cast<size_t>(width) * height);
  const double cx = 0.5 * (width - 1), cy = 0.5 * (height - 1);
  const double r2max = cx * cx + cy * cy;
  for (int v = 0; v < height; ++v) {
    for (int u = 0; u < width; ++u) {
      const int i = v * width + u;
      const Hit& h = nominal[i];
      bool boundary = false;
      for (const auto& [du, dv] : {std::pair{1, 0}, {-1, 0}, {0, 1}, {0, -1}}) {
        const int uu = u + du, vv = v + dv;
        if (uu < 0 || vv < 0 || uu >= width || vv >= height) continue;
        const Hit& o = nominal[vv * width + uu];
        if (o.object != h.object || o.face != h.face || std::abs(o.depth - h.depth) > 0.01) {
          boundary = true;
        }
      }
      Eigen::Vector3d c = Eigen::Vector3d::Zero();
      if (boundary) {
        for (int sv = -1; sv <= 1; ++sv) {
          for (int su = -1; su <= 1; ++su) {
            const double uu = u + su / 3.0, vv = v + sv / 3.0;
            c += shade(caster.Cast(uu, vv), uu, vv);
          }
        }
        c /= 9.0;
      } else {
        c = shade(h, u, v);
      }
      const double r2 = ((u - cx) * (u - cx) + (v - cy) * (v - cy)) / r2max;
      c *= exposure * (1.0 - 0.25 * r2);  // vignetting
      // Sensor noise in 8-bit levels, after the tone curve.
      uint32_t packed = PackColor(c), out = 0;
      for (int ch = 2; ch >= 0; --ch) {
        const double level = ((packed >> (8 * ch)) & 0xFF) + options.noise_sigma * normal(rng);
        out = (out << 8) | static_cast<uint32_t>(std::clamp<long>(std::lround(level), 0, 255));
      }
      rgb[i] = out;
    }
  }
  return rgb;
}

}  // namespace cornerpose::testing::internal
