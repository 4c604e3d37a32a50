// Render: the nominal ray cast, masks and ground truth, then the noise model.
#include "tests/support/scene_generator.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>

#include "tests/support/color_render.h"
#include "tests/support/kinect_noise.h"
#include "tests/support/ray_caster.h"
#include "tests/support/stereo_noise.h"
#include "tests/support/surface_texture.h"
#include "tests/support/tof_noise.h"

namespace cornerpose::testing {
namespace {

using internal::Hit;
using internal::RayCaster;

// Pixels of box i rendered alone, per face, over integer pixel centres of
// its projected rectangle, which may extend past the image (an unbounded
// image plane). Only a box reaching behind the camera is clipped to the image.
std::array<int, 6> AloneFacePixels(const RayCaster& caster, int i, const CameraIntrinsics& cam) {
  const internal::Rect& rect = caster.cuboids()[i].camera_rect;
  // Guard against boxes almost in the camera plane, whose rectangle explodes.
  const double kMargin = 4.0;
  const int u0 = rect.bounded() ? std::max<int>(std::ceil(rect.u0), -kMargin * cam.width) : 0;
  const int u1 = rect.bounded() ? std::min<int>(std::floor(rect.u1), (kMargin + 1) * cam.width)
                                : cam.width - 1;
  const int v0 = rect.bounded() ? std::max<int>(std::ceil(rect.v0), -kMargin * cam.height) : 0;
  const int v1 = rect.bounded() ? std::min<int>(std::floor(rect.v1), (kMargin + 1) * cam.height)
                                : cam.height - 1;
  std::array<int, 6> count{};
  for (int v = v0; v <= v1; ++v) {
    for (int u = u0; u <= u1; ++u) {
      const Hit hit = caster.CastCuboid(i, u, v);
      if (hit.object == i) ++count[hit.face];
    }
  }
  return count;
}

GroundTruthBox MakeGroundTruth(const Scene& scene, const RayCaster& caster, int i,
                               const std::vector<uint8_t>& instance,
                               const std::vector<uint8_t>& face) {
  const SceneBox& box = scene.boxes[i];
  GroundTruthBox gt;
  gt.dims = box.dims;
  gt.camera_T_box = scene.world_T_camera.inverse() * box.world_T_box;
  gt.target = box.target;

  const std::array<int, 6> alone = AloneFacePixels(caster, i, scene.camera);
  std::array<int, 6> visible{};
  for (size_t p = 0; p < instance.size(); ++p) {
    if (instance[p] == i + 1) ++visible[face[p] - 1];
  }
  const int grasp = static_cast<int>(std::max_element(alone.begin(), alone.end()) - alone.begin());
  for (int f = 0; f < 6; ++f) {
    gt.px_visible += visible[f];
    gt.px_unoccluded += alone[f];
  }
  gt.visib_fract = gt.px_unoccluded > 0 ? double(gt.px_visible) / gt.px_unoccluded : 0.0;
  gt.grasp_face = static_cast<BoxFace>(grasp);
  gt.grasp_px_visible = visible[grasp];
  gt.grasp_px_unoccluded = alone[grasp];
  gt.pickable = gt.target && gt.grasp_px_unoccluded >= 100 &&
                gt.grasp_px_visible >= 0.75 * gt.grasp_px_unoccluded;
  return gt;
}

}  // namespace

Eigen::Isometry3d LookAtCamera(const Eigen::Vector3d& look_at_world, double distance_m,
                               double tilt_deg, double yaw_deg, double roll_deg) {
  constexpr double kDeg = std::numbers::pi / 180.0;
  // Straight down: image x = world +x, image y = world -y, optical axis -z.
  Eigen::Matrix3d down;
  down << 1, 0, 0, 0, -1, 0, 0, 0, -1;
  // Tilting about world x moves the optical axis towards the image top (+y).
  const Eigen::Matrix3d R = Eigen::AngleAxisd(yaw_deg * kDeg, Eigen::Vector3d::UnitZ()) *
                            Eigen::AngleAxisd(tilt_deg * kDeg, Eigen::Vector3d::UnitX()) * down *
                            Eigen::AngleAxisd(roll_deg * kDeg, Eigen::Vector3d::UnitZ());
  Eigen::Isometry3d world_T_camera = Eigen::Isometry3d::Identity();
  world_T_camera.linear() = R;
  world_T_camera.translation() = look_at_world - distance_m * R.col(2);
  return world_T_camera;
}

RenderedScene Render(const Scene& scene, const NoiseOptions& noise) {
  SensorOptions sensor;
  sensor.kinect = noise;
  return Render(scene, sensor);
}

RenderedScene Render(const Scene& scene, const SensorOptions& sensor) {
  const CameraIntrinsics& cam = scene.camera;
  const int width = cam.width, height = cam.height, n = width * height;
  const NoiseOptions& noise = sensor.kinect;
  // The "projector" is whatever must see a point besides the camera: the
  // Kinect's IR projector, the stereo pair's right imager; none for ToF.
  const double offset = sensor.kind == SensorKind::kKinect   ? noise.projector_offset_m
                        : sensor.kind == SensorKind::kStereo ? sensor.stereo.baseline_m
                                                             : 0.0;
  const RayCaster caster(scene, offset);

  RenderedScene out;
  out.camera = cam;
  out.floor_plane_camera = caster.floor_plane();

  // Pass 1: nominal rays through pixel centres give masks and the z-buffer.
  std::vector<Hit> nominal(n);
  out.instance.assign(n, 0);
  out.face.assign(n, 0);
  const int num_boxes = caster.num_boxes();
  for (int v = 0; v < height; ++v) {
    for (int u = 0; u < width; ++u) {
      const int i = v * width + u;
      nominal[i] = caster.Cast(u, v);
      const int object = nominal[i].object;
      if (object >= num_boxes) {
        out.instance[i] = 255;
      } else if (object >= 0) {
        out.instance[i] = static_cast<uint8_t>(std::min(object + 1, 254));
        out.face[i] = static_cast<uint8_t>(nominal[i].face + 1);
      }
    }
  }
  for (int i = 0; i < num_boxes; ++i) {
    out.boxes.push_back(MakeGroundTruth(scene, caster, i, out.instance, out.face));
  }

  const internal::SurfaceTexture texture(scene, caster);
  std::vector<double> depth(n, std::numeric_limits<double>::quiet_NaN());
  std::mt19937 rng(scene.noise_seed);
  std::vector<uint32_t> infrared;
  if (sensor.kind == SensorKind::kStereo) {
    depth =
        internal::ApplyStereoNoise(caster, texture, cam, sensor.stereo, nominal, rng, &out.stats);
  } else if (sensor.kind == SensorKind::kTimeOfFlight) {
    depth = internal::ApplyTofNoise(caster, texture, cam, sensor.tof, nominal, rng, &out.stats,
                                    sensor.color.enabled ? &infrared : nullptr);
  } else if (noise.enabled) {
    depth = internal::ApplyKinectNoise(caster, cam, noise, nominal, rng, &out.stats);
  } else {
    for (int i = 0; i < n; ++i) {
      const double z = nominal[i].depth;
      if (z >= noise.min_range_m && z <= noise.max_range_m) {
        depth[i] = z;
        ++out.stats.valid;
      } else {
        ++out.stats.no_return;
      }
    }
  }

  out.cloud.width = width;
  out.cloud.height = height;
  out.cloud.xyz.resize(n);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int i = 0; i < n; ++i) {
    const double z = depth[i];
    out.cloud.xyz[i] = std::isnan(z) ? Eigen::Vector3f(nan, nan, nan)
                                     : (z * caster.Ray(i % width, i / width)).cast<float>();
  }
  if (sensor.color.enabled) {
    // Time of flight sees its own infrared light; the others a colour camera.
    out.cloud.rgb = sensor.kind == SensorKind::kTimeOfFlight
                        ? std::move(infrared)
                        : internal::RenderColor(scene, caster, texture, nominal, sensor.color,
                                                scene.LookSeed() ^ 0xC0105EEDu);
  }
  return out;
}

}  // namespace cornerpose::testing
