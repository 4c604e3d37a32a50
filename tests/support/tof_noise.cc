#include "tests/support/tof_noise.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <numbers>

#include "tests/support/color_render.h"
#include "tests/support/kinect_noise.h"
#include "tests/support/pixel_status.h"

namespace cornerpose::testing::internal {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// Half the wavelength of an 80 MHz modulation: the unambiguous range, m.
constexpr double kHalfWavelength = 299792458.0 / (2.0 * 80e6);

// Too weak a return.
constexpr PixelStatus kWeak = kGrazing;

// Near-infrared reflectance from the visible albedo: cardboard, wood and
// concrete are brighter in the NIR than they look; black print stays dark.
double InfraredAlbedo(double luma) { return std::clamp(1.6 * luma, 0.02, 0.95); }

// Returned amplitude, relative: albedo cos(theta) / r^2 (r the radial
// distance), times the illuminator's beam falloff cos(off-axis angle)^3.
double Amplitude(double albedo, const Eigen::Vector3d& normal, const Eigen::Vector3d& p) {
  const double r = p.norm(), beam = p.z() / r;
  return albedo * std::max(0.0, -normal.dot(p) / r) / (r * r) * beam * beam * beam;
}

}  // namespace

std::vector<double> ApplyTofNoise(const RayCaster& caster, const SurfaceTexture& texture,
                                  const CameraIntrinsics& camera, const TofOptions& options,
                                  const std::vector<Hit>& nominal, std::mt19937& rng,
                                  RenderStats* stats, std::vector<uint32_t>* infrared) {
  const int width = camera.width, height = camera.height, n = width * height;
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::normal_distribution<double> normal;
  std::vector<uint8_t> status(n, kValid);
  std::vector<double> range(n, kNaN), amplitude(n, 0.0), albedo(n, 0.0);
  std::vector<Eigen::Vector3d> point(n, Eigen::Vector3d::Zero());
  for (int i = 0; i < n; ++i) {
    const Hit& h = nominal[i];
    if (h.object == kNothing) {
      status[i] = kNoReturn;
      continue;
    }
    point[i] = h.depth * caster.Ray(i % width, i / width);
    albedo[i] = InfraredAlbedo(texture.Luma(h, point[i]));
    amplitude[i] = Amplitude(albedo[i], h.normal, point[i]);
    range[i] = point[i].norm();
  }

  // 1. Mixed pixels: where the footprint straddles a jump, the phasors of
  // its 3 x 3 sub-rays add up, weighted by their amplitudes.
  std::vector<double> mixed = range;
  for (int i = 0; i < n; ++i) {
    const int u = i % width, v = i / width;
    bool jump = false;
    for (const auto& [du, dv] : {std::pair{1, 0}, {-1, 0}, {0, 1}, {0, -1}}) {
      const int uu = u + du, vv = v + dv;
      if (uu < 0 || vv < 0 || uu >= width || vv >= height) continue;
      const Hit& o = nominal[vv * width + uu];
      if (o.object == kNothing || nominal[i].object == kNothing ||
          std::abs(o.depth - nominal[i].depth) > options.mixed_jump_m) {
        jump = true;
      }
    }
    if (!jump) continue;
    std::complex<double> sum = 0.0;
    double a_sum = 0.0, r_lo = 1e9, r_hi = 0.0;
    for (int sv = -1; sv <= 1; ++sv) {
      for (int su = -1; su <= 1; ++su) {
        const double uu = u + su / 3.0, vv = v + sv / 3.0;
        const Hit h = caster.Cast(uu, vv);
        if (h.object == kNothing) continue;
        const Eigen::Vector3d p = h.depth * caster.Ray(uu, vv);
        const double a = Amplitude(InfraredAlbedo(texture.Luma(h, p)), h.normal, p);
        const double r = p.norm();
        sum += a * std::polar(1.0, 2.0 * std::numbers::pi * r / kHalfWavelength);
        a_sum += a;
        r_lo = std::min(r_lo, r);
        r_hi = std::max(r_hi, r);
      }
    }
    if (a_sum <= 0.0) continue;
    double phase = std::arg(sum);
    if (phase < 0) phase += 2.0 * std::numbers::pi;
    double r = phase / (2.0 * std::numbers::pi) * kHalfWavelength;
    // Back to the wrap the surfaces are in (ranges beyond one wavelength).
    const double base = std::floor(r_lo / kHalfWavelength) * kHalfWavelength;
    r += base;
    if (r < r_lo - 0.5 * kHalfWavelength) r += kHalfWavelength;
    mixed[i] = r;
    amplitude[i] = std::abs(sum) / 9.0;
    if (r_hi - r_lo > options.mixed_jump_m) {
      if (status[i] == kValid && uniform(rng) < options.invalidate_mixed_prob) {
        status[i] = kDropout;
      } else if (status[i] == kValid) {
        ++stats->flying;
      }
    }
    if (status[i] == kNoReturn && a_sum > 0.0) status[i] = kValid;  // a partial return
  }
  range = mixed;

  // 2. Multipath: light the camera sent to a nearby surface q that faces p
  // reaches p too, over a longer path (screen space, K samples in a disc).
  constexpr int kSamples = 16;
  std::vector<double> bias(n, 0.0);
  if (options.multipath_gain > 0.0) {
    for (int i = 0; i < n; ++i) {
      if (status[i] != kValid || nominal[i].object == kNothing) continue;
      const Eigen::Vector3d& p = point[i];
      const Eigen::Vector3d& np = nominal[i].normal;
      const double direct = amplitude[i] / std::max(albedo[i], 1e-6);
      if (direct <= 0.0) continue;
      const double radius_px = camera.fx * options.multipath_radius_m / p.z();
      const double sample_px = std::numbers::pi * radius_px * radius_px / kSamples;
      const int u = i % width, v = i / width;
      double ratio = 0.0, excess = 0.0;
      for (int k = 0; k < kSamples; ++k) {
        const double rr = radius_px * std::sqrt((k + 0.5) / kSamples);
        const double phi = k * 2.399963 + 0.7 * (i % 7);
        const int uu = static_cast<int>(std::lround(u + rr * std::cos(phi)));
        const int vv = static_cast<int>(std::lround(v + rr * std::sin(phi)));
        if (uu < 0 || vv < 0 || uu >= width || vv >= height) continue;
        const int j = vv * width + uu;
        if (nominal[j].object == kNothing) continue;
        const Eigen::Vector3d d = point[j] - p;
        const double dist = d.norm();
        if (dist < 1e-3) continue;
        const double cos_p = np.dot(d) / dist, cos_q = -nominal[j].normal.dot(d) / dist;
        if (cos_p <= 0.0 || cos_q <= 0.0) continue;
        const Eigen::Vector3d& q = point[j];
        const double cos_q_cam = std::max(0.0, -nominal[j].normal.dot(q) / q.norm());
        if (cos_q_cam <= 1e-3) continue;
        const double area = sample_px * q.z() * q.z() / (camera.fx * camera.fx) / cos_q_cam;
        // Irradiance at q (its amplitude) reflected diffusely towards p.
        const double w = amplitude[j] / std::numbers::pi * cos_p * cos_q / (dist * dist) * area;
        ratio += w;
        excess += w * 0.5 * (q.norm() + dist - p.norm());
      }
      ratio *= options.multipath_gain / direct;
      if (ratio <= 0.0) continue;
      // Phasor mix of the direct return (weight 1) and the indirect one.
      bias[i] = excess * options.multipath_gain / direct / (1.0 + ratio);
      if (bias[i] > 1e-3) ++stats->multipath;
    }
  }

  // 3. Noise from the return's strength; too weak a return is invalid.
  const std::vector<double> field = SmoothGaussianField(width, height, options.correlation_px, rng);
  std::vector<double> depth(n, kNaN);
  for (int i = 0; i < n; ++i) {
    if (status[i] != kValid) continue;
    if (amplitude[i] < options.min_amplitude) {
      status[i] = kWeak;
      continue;
    }
    const double sigma = std::min(0.05, options.sigma_ref_m * std::sqrt(0.5 / amplitude[i]));
    const double r = range[i] + bias[i] + sigma * (normal(rng) + field[i]) / std::numbers::sqrt2;
    const Eigen::Vector3d ray = caster.Ray(i % width, i / width);
    depth[i] = r / ray.norm();  // camera z of the measured radial distance
  }

  // 4. Random dropouts, the working range and output units.
  for (int i = 0; i < n; ++i) {
    if (status[i] == kValid && uniform(rng) < options.dropout_prob) status[i] = kDropout;
  }
  FinishPixels(status, options.min_range_m, options.max_range_m, options.output_step_m, depth,
               stats);

  if (infrared != nullptr) {
    infrared->assign(n, 0);
    for (int i = 0; i < n; ++i) {
      const double level = std::clamp(1.2 * amplitude[i] + 0.004 * normal(rng), 0.0, 1.0);
      const uint32_t g = PackColor(Eigen::Vector3d::Constant(level)) & 0xFF;
      (*infrared)[i] = (g << 16) | (g << 8) | g;
    }
  }
  return depth;
}

}  // namespace cornerpose::testing::internal
