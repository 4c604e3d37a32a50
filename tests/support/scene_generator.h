// Synthetic depth frames of boxes with exact ground truth, for tests.
//
// Mirrors the generator of the dev set (shared/tools/README.md): boxes and
// support parts are ray cast (slab method) against a floor at world z = 0,
// then a Kinect-v1-like noise model is applied. Independent of PCL.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <vector>

#include "common/perception/types.h"
#include "tests/support/sensor_options.h"

namespace cornerpose::testing {

// A box to render. Box frame at the centroid, x along l, y along b, z along h.
struct SceneBox {
  BoxDims dims;
  Eigen::Isometry3d world_T_box = Eigen::Isometry3d::Identity();
  bool target = true;  // false: a distractor of another size
};

// One cuboid of a support structure (pallet board, table top, leg).
// Supports are labelled 255 in the instance mask and have no ground truth.
struct SupportPart {
  std::string name;
  BoxDims dims;
  Eigen::Isometry3d world_T_part = Eigen::Isometry3d::Identity();
};

struct Scene {
  CameraIntrinsics camera;
  // Camera frame: x right, y down, z forward. World: z up, floor at z = 0.
  Eigen::Isometry3d world_T_camera = Eigen::Isometry3d::Identity();
  std::vector<SceneBox> boxes;  // at most 254 (instance labels 1..254)
  std::vector<SupportPart> supports;
  bool floor = true;
  uint32_t noise_seed = 1;  // seeds Render's noise: same seed, same cloud
  // Seeds the surfaces' look (shades, tape, print, infrared albedo) and the
  // colour image's light; 0: noise_seed. A recording of one scene keeps the
  // look and draws new noise per frame (make_frames --take_every).
  uint32_t look_seed = 0;
  uint32_t LookSeed() const { return look_seed != 0 ? look_seed : noise_seed; }
};

// A camera looking down at look_at_world from distance_m along its optical
// axis. tilt_deg is the angle of the optical axis from straight down, yaw_deg
// turns the camera about the world vertical, roll_deg about its optical axis.
// With all angles 0 the image x axis is world +x and image y is world -y.
Eigen::Isometry3d LookAtCamera(const Eigen::Vector3d& look_at_world, double distance_m,
                               double tilt_deg, double yaw_deg, double roll_deg);

// Kinect v1 noise, applied in the order of the fields below. Defaults follow
// the dev set; a probability or sigma of 0 turns that step off.
struct NoiseOptions {
  bool enabled = true;  // false: exact depth of the nominal rays (range still applies)

  // 1. Lateral: rays re-cast through jittered pixel positions, sigma
  // 0.8 + 0.035 theta / (pi/2 - theta) px, half white, half correlated.
  double lateral_sigma_px = 0.8;
  double lateral_correlation_px = 2.0;
  // 2. Projector shadow: no pattern where the projector is blocked or faces away.
  bool projector_shadow = true;
  double projector_offset_m = 0.075;  // along camera +x
  // 3. Grazing dropout: p = clip((theta_eff - start) / (max - start), 0, 1)^1.5,
  // theta_eff the larger of camera and projector incidence, max drawn per scene.
  bool grazing_dropout = true;
  double grazing_start_deg = 65.0;
  double grazing_max_deg_min = 78.0;
  double grazing_max_deg_max = 84.0;
  double grazing_correlation_px = 3.0;  // dropouts come in coherent patches
  // 4. Flying pixels at depth jumps: z + a (z_nb - z), a ~ U(0.15, 0.85).
  double flying_prob = 0.25;
  double flying_jump_m = 0.02;
  // 5. Axial noise sigma_z = 1.2e-3 + 1.9e-3 (z - 0.4)^2 m (+ a grazing term),
  // then disparity quantization and 1 mm output rounding.
  bool axial_noise = true;
  double axial_correlation_px = 1.5;
  bool quantize = true;
  double ir_focal_px = 580.0;
  double baseline_m = 0.075;
  double disparity_step_px = 0.125;
  double output_step_m = 0.001;
  // 6. Dropouts: random pixels and small elliptic blobs.
  double dropout_prob = 0.002;
  int num_blobs = 3;
  // Valid range, applied even when disabled.
  double min_range_m = 0.5;
  double max_range_m = 4.0;
};

struct GroundTruthBox {
  BoxDims dims;
  Eigen::Isometry3d camera_T_box = Eigen::Isometry3d::Identity();
  bool target = true;
  int px_visible = 0;  // pixels labelled with this box in the instance mask
  // Pixels it covers rendered alone on an unbounded image plane (pixel
  // centres past the border count; clipped to the image only for a box that
  // reaches behind the camera, and to 4 image sizes around it).
  int px_unoccluded = 0;
  double visib_fract = 0.0;
  BoxFace grasp_face = BoxFace::kPlusZ;  // most pixels when rendered alone
  int grasp_px_visible = 0;
  int grasp_px_unoccluded = 0;
  // target, and the grasp face has >= 100 px of which >= 75 % are visible.
  bool pickable = false;
};

// Where the invalid pixels came from (a pixel counts once, first cause wins).
struct RenderStats {
  int valid = 0;
  int no_return = 0;  // ray hit nothing (sky) or out of range
  int shadow = 0;
  int grazing = 0;
  int flying = 0;     // valid but moved to a mixed depth
  int dropout = 0;    // random and speckle holes, blobs, low signal (tof)
  int filled = 0;     // valid, depth taken from the sides of a thin gap or hole (stereo)
  int multipath = 0;  // valid, biased by more than 1 mm by multipath (tof)
};

struct RenderedScene {
  // Organized, camera frame, NaN where invalid. With colour rendering on,
  // cloud.rgb holds the registered image (0x00RRGGBB, every pixel, valid
  // depth or not; grey infrared intensity for time of flight).
  PointCloud cloud;
  CameraIntrinsics camera;
  // Per pixel, from the noise-free nominal rays: 0 floor/nothing,
  // k = boxes[k-1], 255 support.
  std::vector<uint8_t> instance;
  // Per pixel: 0 not a box, 1..6 face +x,-x,+y,-y,+z,-z of the box in instance.
  std::vector<uint8_t> face;
  std::vector<GroundTruthBox> boxes;                             // same order as Scene::boxes
  Eigen::Vector4d floor_plane_camera = Eigen::Vector4d::Zero();  // normal towards the camera
  RenderStats stats;
};

RenderedScene Render(const Scene& scene, const NoiseOptions& noise = {});

// A sensor model and the colour image. The Kinect model with the same
// NoiseOptions gives exactly the depth of Render(scene, kinect); colour
// draws on its own random stream, so turning it on changes no depth.
struct SensorOptions {
  SensorKind kind = SensorKind::kKinect;
  NoiseOptions kinect;
  StereoOptions stereo;
  TofOptions tof;
  ColorOptions color;

  absl::Status Validate() const;
};
RenderedScene Render(const Scene& scene, const SensorOptions& sensor);

// Where the scene builders put the camera: its intrinsics (they become
// Scene::camera) and the range of its distance to the scene's look-at point
// and of its tilt. A distance or tilt below 0 keeps each builder's own
// default (the Kinect dev-set ranges below), and the default placement
// gives the same scenes as the builders without one.
struct CameraPlacement {
  CameraIntrinsics intrinsics;
  double min_distance_m = -1.0;
  double max_distance_m = -1.0;
  double max_tilt_deg = -1.0;
  // Every box corner at least this deep in the camera frame: the camera backs
  // off along its axis until it is, as a cell is laid out with the tallest
  // box inside the sensor's working range (a heap's top box 0.3 m above the
  // look-at point was nearer than a stereo camera's range and returned no
  // depth at all). Metres; -1: no limit.
  double min_depth_m = -1.0;
};
// A placement fit for a sensor's working range: kinect keeps the defaults;
// stereo 1.3-2.0 m (look-at point to camera), tilt 0-20 deg, every box at
// least 5 cm beyond the near end of its range; tof 1.0-1.8 m, tilt 0-20 deg.
CameraPlacement SensorPlacement(SensorKind kind, const CameraIntrinsics& intrinsics);

// Scene builders. The seed fixes the layout, the camera and the noise.

// num_boxes boxes lying flat (h vertical) on the floor, random yaw, at least
// 6 cm apart, all fully in view; camera 0.9-1.3 m away, tilt 0-20 deg.
Scene MakeIsolatedScene(const BoxDims& dims, int num_boxes, uint32_t seed,
                        const CameraPlacement& placement = {});

// A heap of touching, stacked and tilted boxes on the floor: boxes slide in
// until they touch the heap, or are dropped onto it (tilted up to 30 deg,
// lowest centre kept). No two boxes interpenetrate.
// Camera 1.0-1.5 m, tilt 0-25 deg.
Scene MakeHeapScene(const BoxDims& dims, int num_boxes, uint32_t seed,
                    const CameraPlacement& placement = {});

// The demo cell's view: a heap (as MakeHeapScene) around the world origin
// seen by a camera fixed kCellCameraHeight straight above the origin
// (image x = world +x, image y = world -y), the mounting the robot cell's
// hand-eye calibration (deploy/config/robot_client.textproto) describes.
inline constexpr double kCellCameraHeight = 1.3;
Scene MakeCellScene(const BoxDims& dims, int num_boxes, uint32_t seed);

// A rows x cols x layers grid on a EUR pallet, l along the pallet length,
// gap_m between boxes, +-2 mm / +-0.6 deg jitter; removed_top boxes of the top
// layer are taken away row by row from a corner. Camera 1.1-1.5 m above the
// top layer, tilt 0-20 deg.
Scene MakePalletScene(const BoxDims& dims, int rows, int cols, int layers, double gap_m,
                      int removed_top, uint32_t seed, const CameraPlacement& placement = {});

// As MakePalletScene, and then num_distractors of the top layer's remaining
// boxes are replaced by boxes of another size (target false: 55-85 % of the
// length, 60-90 % of the width, 60-130 % of the height), each pushed against
// a side of its cell. With 0 distractors this is MakePalletScene.
Scene MakeDistractorPalletScene(const BoxDims& dims, int rows, int cols, int layers, double gap_m,
                                int removed_top, int num_distractors, uint32_t seed,
                                const CameraPlacement& placement = {});

// Support structures. The pallet frame sits at the centre of its footprint on
// the ground, x along the 1.2 m side; its deck is kEurPalletHeight high.
inline constexpr double kEurPalletHeight = 0.144;
std::vector<SupportPart> MakeEurPallet(const Eigen::Isometry3d& world_T_pallet);
// A table: top slab (its upper face at height_m) and four legs; the frame sits
// at the centre of its footprint on the ground.
std::vector<SupportPart> MakeTable(const Eigen::Isometry3d& world_T_table, double length_m = 1.4,
                                   double width_m = 0.9, double height_m = 0.75);

}  // namespace cornerpose::testing
