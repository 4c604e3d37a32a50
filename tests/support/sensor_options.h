// Options of the generator's depth sensor models besides Kinect v1 (active
// stereo, time of flight) and of its colour rendering. Each struct documents
// its defaults (unit, range); Validate() names the field it rejects.
#pragma once

#include <string>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "common/perception/types.h"

namespace cornerpose::testing {

// Which sensor family renders the depth.
enum class SensorKind {
  kKinect,  // structured light, Kinect v1 / Xtion (NoiseOptions)
  kTimeOfFlight,  // Kinect v2 / Azure Kinect class (TofOptions)
  kStereo,  // active stereo, RealSense D4xx class (StereoOptions)
};
const char* SensorKindName(SensorKind kind);  // "kinect", "tof", "stereo"
absl::StatusOr<SensorKind> ParseSensorKind(const std::string& name);

// The sensor's pinhole at a resolution it offers: kinect 640x480 (fx 525);
// tof 512x424 (fx 365, Kinect v2) or 640x576 (fx 505, Azure Kinect NFOV);
// stereo 640x480 (fx 607) or 1280x720 (fx 910, the same lens, 16:9 mode).
// width = height = 0 picks the sensor's first resolution. INVALID_ARGUMENT
// for a resolution the sensor does not offer.
absl::StatusOr<CameraIntrinsics> SensorIntrinsics(SensorKind kind, int width = 0, int height = 0);

// Active stereo (RealSense D4xx-like), applied in the order of the fields.
// Depth is that of the left imager; the right imager sits baseline_m along +x.
struct StereoOptions {
  // 1. Thin-gap fill: the matching window cannot resolve a crack narrower
  // than this (touching boxes' seams, 0-3 mm gaps), which gets the depth of
  // its sides. Pixels, [0, 15]; 0 turns it off.
  int gap_fill_px = 4;
  // 2. Edge fattening: the nearer surface grows into the farther one by this
  // many pixels at every occluding border (depth jump > jump_m). Pixels, [0, 5].
  int fattening_px = 1;
  double jump_m = 0.03;  // m, (0, 1]
  // 3. Flying pixels: a pixel next to a jump becomes, with this probability,
  // a mix z + a (z_nb - z), a ~ U(0.15, 0.85). [0, 1].
  double flying_prob = 0.3;
  // 4. Left occlusion: no match where the right imager cannot see the point
  // (hidden behind a nearer surface or outside its image), widened by the
  // matching window's half width on the occluded side. baseline m, (0, 0.5];
  // margin px, [0, 10].
  double baseline_m = 0.05;
  int occlusion_margin_px = 3;
  // 5. Depth noise from disparity noise: sigma_z = z^2 sigma_d / (fx baseline),
  // sigma_d = subpixel_px, times 1 / sqrt(cos(incidence)) for foreshortened
  // texture. Correlated over the matching window: white, window-scale and
  // blob-scale parts (shares of the variance, each [0, 1], summing to 1).
  double subpixel_px = 0.08;  // px, [0, 1]
  double white_share = 0.1;
  double window_share = 0.45;
  double window_correlation_px = 2.5;  // px, (0, 20]
  double blob_correlation_px = 9.0;    // px, (0, 50]
  // 6. Holes: random speckle holes where the projected texture is weak
  // (dark surfaces, print): p = speckle_prob + dark_hole_prob * (1 - albedo /
  // dark_albedo)^2 for albedo (the surface's luminance) < dark_albedo, in
  // coherent patches; no match beyond grazing_max_deg incidence; then small
  // holes (<= hole_fill_px wide) are filled from their neighbours as the
  // camera's hole filling does. Probabilities [0, 1]; dark_albedo (0, 1];
  // grazing_max_deg (60, 90]; hole_fill_px [0, 10].
  double speckle_prob = 0.003;
  double dark_hole_prob = 0.6;
  double dark_albedo = 0.12;
  double grazing_max_deg = 82.0;  // no match beyond this incidence angle
  int hole_fill_px = 2;
  // 7. Working range, m: depths outside [min_range_m, max_range_m] are dropped.
  double min_range_m = 1.2;
  double max_range_m = 2.5;
  double output_step_m = 0.001;  // depth units of the output, m, [0, 0.01]

  absl::Status Validate() const;
};

// Time of flight (Kinect v2 / Azure Kinect class), applied in this order.
struct TofOptions {
  // 1. Mixed pixels: a pixel whose footprint straddles a depth jump returns
  // the amplitude-weighted mix of both surfaces (3x3 sub-rays per pixel at
  // jumps > mixed_jump_m); with invalidate_mixed_prob such a pixel is
  // dropped (the camera's own filter), otherwise it flies between them.
  double mixed_jump_m = 0.01;  // m, (0, 1]
  double invalidate_mixed_prob = 0.4;  // [0, 1]
  // 2. Multipath: light reaching a pixel via a nearby surface facing it (a
  // concave crease: box meets floor or box) adds a longer path; the depth
  // is biased away from the camera by up to about multipath_gain * 25 mm
  // right at the crease. multipath_radius_m is how far the neighbourhood
  // reaches. gain [0, 10], radius m (0, 1].
  double multipath_gain = 1.0;
  double multipath_radius_m = 0.15;
  // 3. Noise from the return's strength: amplitude a = albedo cos(theta) /
  // r^2 cos(phi)^3 (albedo of the surface in IR, phi the angle off the
  // illuminator's axis), sigma_z = sigma_ref_m *
  // sqrt(a_ref / a), a_ref = 0.5 at 1 m, head on. Below min_amplitude the
  // pixel is invalid. sigma m [0, 0.05]; min_amplitude [0, 1].
  double sigma_ref_m = 0.0015;
  double min_amplitude = 0.02;
  double correlation_px = 0.8;  // mostly white noise, px [0, 10]
  double dropout_prob = 0.001;  // random invalid pixels [0, 1]
  // 4. Working range, m.
  double min_range_m = 0.5;
  double max_range_m = 4.5;
  double output_step_m = 0.001;  // m, [0, 0.01]

  absl::Status Validate() const;
};

// The registered colour image (or infrared intensity for time of flight).
struct ColorOptions {
  bool enabled = false;
  // Light from above: elevation from the horizontal drawn in this range per
  // scene, deg (0, 90]; ambient share of the light, [0, 1].
  double light_elevation_min_deg = 50.0;
  double light_elevation_max_deg = 80.0;
  double ambient = 0.4;
  double light_size_deg = 6.0;  // soft shadows: the light's angular radius, [0, 30]
  int shadow_samples = 4;       // rays towards the light per pixel, [1, 16]
  double noise_sigma = 1.5;     // sensor noise, 8-bit levels, [0, 20]

  absl::Status Validate() const;
};

}  // namespace cornerpose::testing
