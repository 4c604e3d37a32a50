#include "tests/support/sensor_options.h"

#include <cmath>

#include "absl/strings/str_cat.h"
#include "tests/support/scene_generator.h"

namespace cornerpose::testing {
namespace {

// OK when lo <= value <= hi (and finite), else names the field.
absl::Status InRange(const char* owner, const char* field, double value, double lo, double hi,
                     bool open_lo = false) {
  const bool ok = std::isfinite(value) && (open_lo ? value > lo : value >= lo) && value <= hi;
  if (ok) return absl::OkStatus();
  return absl::InvalidArgumentError(absl::StrCat(owner, ".", field, " = ", value, " is outside ",
                                                 open_lo ? "(" : "[", lo, ", ", hi, "]"));
}

#define CHECK_RANGE(...) \
  if (absl::Status s = InRange(__VA_ARGS__); !s.ok()) return s

}  // namespace

const char* SensorKindName(SensorKind kind) {
  switch (kind) {
    case SensorKind::kKinect:
      return "kinect";
    case SensorKind::kTimeOfFlight:
      return "tof";
    case SensorKind::kStereo:
      return "stereo";
  }
  return "?";
}

absl::StatusOr<SensorKind> ParseSensorKind(const std::string& name) {
  for (SensorKind k : {SensorKind::kKinect, SensorKind::kTimeOfFlight, SensorKind::kStereo}) {
    if (name == SensorKindName(k)) return k;
  }
  return absl::InvalidArgumentError(
      absl::StrCat("unknown sensor '", name, "' (expected kinect, tof or stereo)"));
}

absl::StatusOr<CameraIntrinsics> SensorIntrinsics(SensorKind kind, int width, int height) {
  struct Mode {
    int w, h;
    double f;
  };
  std::vector<Mode> modes;
  switch (kind) {
    case SensorKind::kKinect:
      modes = {{640, 480, 525.0}};
      break;
    case SensorKind::kTimeOfFlight:
      modes = {{512, 424, 365.0}, {640, 576, 505.0}};
      break;
    case SensorKind::kStereo:
      modes = {{640, 480, 607.0}, {1280, 720, 910.0}};
      break;
  }
  std::string offered;
  for (const Mode& m : modes) {
    if ((width == 0 && height == 0) || (m.w == width && m.h == height)) {
      CameraIntrinsics c;
      c.width = m.w;
      c.height = m.h;
      c.fx = c.fy = m.f;
      c.cx = 0.5 * (m.w - 1);
      c.cy = 0.5 * (m.h - 1);
      return c;
    }
    absl::StrAppend(&offered, offered.empty() ? "" : ", ", m.w, "x", m.h);
  }
  return absl::InvalidArgumentError(absl::StrCat("sensor ", SensorKindName(kind),
                                                 " has no resolution ", width, "x", height,
                                                 " (it offers ", offered, ")"));
}

CameraPlacement SensorPlacement(SensorKind kind, const CameraIntrinsics& intrinsics) {
  CameraPlacement p;
  p.intrinsics = intrinsics;
  if (kind == SensorKind::kStereo) {
    p.min_distance_m = 1.3;
    p.max_distance_m = 2.0;
    p.max_tilt_deg = 20.0;
    p.min_depth_m = StereoOptions{}.min_range_m + 0.05;
  } else if (kind == SensorKind::kTimeOfFlight) {
    p.min_distance_m = 1.0;
    p.max_distance_m = 1.8;
    p.max_tilt_deg = 20.0;
  }
  return p;
}

absl::Status StereoOptions::Validate() const {
  const char* o = "StereoOptions";
  CHECK_RANGE(o, "gap_fill_px", gap_fill_px, 0, 15);
  CHECK_RANGE(o, "fattening_px", fattening_px, 0, 5);
  CHECK_RANGE(o, "jump_m", jump_m, 0, 1, true);
  CHECK_RANGE(o, "flying_prob", flying_prob, 0, 1);
  CHECK_RANGE(o, "baseline_m", baseline_m, 0, 0.5, true);
  CHECK_RANGE(o, "occlusion_margin_px", occlusion_margin_px, 0, 10);
  CHECK_RANGE(o, "subpixel_px", subpixel_px, 0, 1);
  CHECK_RANGE(o, "white_share", white_share, 0, 1);
  CHECK_RANGE(o, "window_share", window_share, 0, 1 - white_share);
  CHECK_RANGE(o, "window_correlation_px", window_correlation_px, 0, 20, true);
  CHECK_RANGE(o, "blob_correlation_px", blob_correlation_px, 0, 50, true);
  CHECK_RANGE(o, "speckle_prob", speckle_prob, 0, 1);
  CHECK_RANGE(o, "dark_hole_prob", dark_hole_prob, 0, 1);
  CHECK_RANGE(o, "dark_albedo", dark_albedo, 0, 1, true);
  CHECK_RANGE(o, "grazing_max_deg", grazing_max_deg, 60, 90, true);
  CHECK_RANGE(o, "hole_fill_px", hole_fill_px, 0, 10);
  CHECK_RANGE(o, "min_range_m", min_range_m, 0, 100);
  CHECK_RANGE(o, "max_range_m", max_range_m, min_range_m, 100, true);
  CHECK_RANGE(o, "output_step_m", output_step_m, 0, 0.01);
  return absl::OkStatus();
}

absl::Status TofOptions::Validate() const {
  const char* o = "TofOptions";
  CHECK_RANGE(o, "mixed_jump_m", mixed_jump_m, 0, 1, true);
  CHECK_RANGE(o, "invalidate_mixed_prob", invalidate_mixed_prob, 0, 1);
  CHECK_RANGE(o, "multipath_gain", multipath_gain, 0, 10);
  CHECK_RANGE(o, "multipath_radius_m", multipath_radius_m, 0, 1, true);
  CHECK_RANGE(o, "sigma_ref_m", sigma_ref_m, 0, 0.05);
  CHECK_RANGE(o, "min_amplitude", min_amplitude, 0, 1);
  CHECK_RANGE(o, "correlation_px", correlation_px, 0, 10);
  CHECK_RANGE(o, "dropout_prob", dropout_prob, 0, 1);
  CHECK_RANGE(o, "min_range_m", min_range_m, 0, 100);
  CHECK_RANGE(o, "max_range_m", max_range_m, min_range_m, 100, true);
  CHECK_RANGE(o, "output_step_m", output_step_m, 0, 0.01);
  return absl::OkStatus();
}

absl::Status ColorOptions::Validate() const {
  const char* o = "ColorOptions";
  CHECK_RANGE(o, "light_elevation_min_deg", light_elevation_min_deg, 0, 90, true);
  CHECK_RANGE(o, "light_elevation_max_deg", light_elevation_max_deg, light_elevation_min_deg, 90);
  CHECK_RANGE(o, "ambient", ambient, 0, 1);
  CHECK_RANGE(o, "light_size_deg", light_size_deg, 0, 30);
  CHECK_RANGE(o, "shadow_samples", shadow_samples, 1, 16);
  CHECK_RANGE(o, "noise_sigma", noise_sigma, 0, 20);
  return absl::OkStatus();
}

absl::Status SensorOptions::Validate() const {
  switch (kind) {
    case SensorKind::kStereo:
      if (absl::Status s = stereo.Validate(); !s.ok()) return s;
      break;
    case SensorKind::kTimeOfFlight:
      if (absl::Status s = tof.Validate(); !s.ok()) return s;
      break;
    case SensorKind::kKinect:
      break;
  }
  return color.enabled ? color.Validate() : absl::OkStatus();
}

}  // namespace cornerpose::testing
