// Random scene layouts: isolated boxes, heaps, pallets, and support parts.
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>

#include "tests/support/obb.h"
#include "tests/support/scene_generator.h"

namespace cornerpose::testing {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;
constexpr double kTouchTol = 1e-9;  // touching boxes are fine, overlapping ones are not

double Uniform(std::mt19937& rng, double lo, double hi) {
  return std::uniform_real_distribution<double>(lo, hi)(rng);
}

Eigen::Isometry3d MakePose(const Eigen::Matrix3d& R, const Eigen::Vector3d& t) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = R;
  pose.translation() = t;
  return pose;
}

Eigen::Matrix3d Yaw(double rad) {
  return Eigen::AngleAxisd(rad, Eigen::Vector3d::UnitZ()).matrix();
}

// Height of the centre above the lowest corner for orientation R.
double RestHeight(const BoxDims& dims, const Eigen::Matrix3d& R) {
  return 0.5 * R.row(2).cwiseAbs().dot(dims.vec());
}

// Keeps the layout and the noise streams apart while staying a function of seed.
uint32_t NoiseSeed(uint32_t seed) { return seed * 2654435761u + 0x9E3779B9u; }

// The builder's own ranges unless the placement sets them.
struct CameraRange {
  double lo, hi, tilt;
};
CameraRange Range(const CameraPlacement& p, double lo, double hi, double tilt) {
  return {p.min_distance_m >= 0 ? p.min_distance_m : lo,
          p.max_distance_m >= 0 ? p.max_distance_m : hi,
          p.max_tilt_deg >= 0 ? p.max_tilt_deg : tilt};
}

void SetRandomCamera(const Eigen::Vector3d& look_at, double dist_lo, double dist_hi,
                     double max_tilt_deg, std::mt19937& rng, Scene* scene) {
  const double distance = Uniform(rng, dist_lo, dist_hi);
  const double tilt = Uniform(rng, 0.0, max_tilt_deg);
  const double yaw = Uniform(rng, 0.0, 360.0);
  const double roll = Uniform(rng, -2.0, 2.0);
  scene->world_T_camera = LookAtCamera(look_at, distance, tilt, yaw, roll);
}

// Moves the camera back along its axis until every box corner is at least
// placement.min_depth_m deep. Draws nothing, so the layout stays the seed's.
void KeepBeyondNearRange(const CameraPlacement& placement, Scene* scene) {
  if (placement.min_depth_m <= 0.0) return;
  const Eigen::Isometry3d camera_T_world = scene->world_T_camera.inverse();
  double nearest = std::numeric_limits<double>::infinity();
  for (const SceneBox& box : scene->boxes) {
    for (const Eigen::Vector3d& corner : BoxCorners(box.dims, camera_T_world * box.world_T_box)) {
      nearest = std::min(nearest, corner.z());
    }
  }
  if (nearest < placement.min_depth_m) {
    scene->world_T_camera.translation() -=
        (placement.min_depth_m - nearest) * scene->world_T_camera.linear().col(2);
  }
}

// All corners in front of the camera and at least margin_px inside the image.
bool FullyInView(const Scene& scene, const BoxDims& dims, const Eigen::Isometry3d& world_T_box,
                 double margin_px) {
  const Eigen::Isometry3d camera_T_world = scene.world_T_camera.inverse();
  const CameraIntrinsics& cam = scene.camera;
  for (const Eigen::Vector3d& corner : BoxCorners(dims, camera_T_world * world_T_box)) {
    if (corner.z() < 0.1) return false;
    const double u = cam.fx * corner.x() / corner.z() + cam.cx;
    const double v = cam.fy * corner.y() / corner.z() + cam.cy;
    if (u < margin_px || v < margin_px || u > cam.width - 1 - margin_px ||
        v > cam.height - 1 - margin_px) {
      return false;
    }
  }
  return true;
}

bool Free(const BoxDims& dims, const Eigen::Isometry3d& pose,
          const std::vector<Eigen::Isometry3d>& placed) {
  if (pose.translation().z() - RestHeight(dims, pose.linear()) < -kTouchTol) return false;
  for (const Eigen::Isometry3d& other : placed) {
    if (ObbSeparation(dims, pose, dims, other) < -kTouchTol) return false;
  }
  return true;
}

// Moves a box from `from` (free) towards `to` in small steps and returns the
// last free position, refined by bisection once it first collides.
Eigen::Vector3d MoveUntilContact(const BoxDims& dims, const Eigen::Matrix3d& R,
                                 const Eigen::Vector3d& from, const Eigen::Vector3d& to,
                                 const std::vector<Eigen::Isometry3d>& placed) {
  const double length = (to - from).norm();
  const int steps = std::max(1, static_cast<int>(std::ceil(length / 0.004)));
  double free_s = 0.0;
  for (int k = 1; k <= steps; ++k) {
    const double s = static_cast<double>(k) / steps;
    if (Free(dims, MakePose(R, from + s * (to - from)), placed)) {
      free_s = s;
      continue;
    }
    double hit_s = s;
    for (int it = 0; it < 30; ++it) {
      const double mid = 0.5 * (free_s + hit_s);
      (Free(dims, MakePose(R, from + mid * (to - from)), placed) ? free_s : hit_s) = mid;
    }
    break;
  }
  return from + free_s * (to - from);
}

// A random resting orientation: mostly h vertical, sometimes on a side or end.
Eigen::Matrix3d RandomOrientation(std::mt19937& rng) {
  const double r = Uniform(rng, 0.0, 1.0);
  Eigen::Matrix3d base = Eigen::Matrix3d::Identity();
  if (r > 0.9) {
    base = Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::UnitY()).matrix();
  } else if (r > 0.75) {
    base = Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::UnitX()).matrix();
  }
  return Yaw(Uniform(rng, 0.0, 2 * std::numbers::pi)) * base;
}

Eigen::Vector2d HeapCentre(const std::vector<Eigen::Isometry3d>& placed) {
  Eigen::Vector2d c = Eigen::Vector2d::Zero();
  for (const auto& p : placed) c += p.translation().head<2>();
  return c / std::max<size_t>(placed.size(), 1);
}

// Slides a box lying on the floor in from afar until it touches the heap.
Eigen::Isometry3d SlideIn(const BoxDims& dims, const Eigen::Matrix3d& R,
                          const std::vector<Eigen::Isometry3d>& placed, std::mt19937& rng) {
  const double size = std::max(dims.l, dims.b);
  std::normal_distribution<double> spread(0.0, 0.3 * size);
  // Drawn one at a time: the order in which a call's arguments are evaluated
  // is unspecified (g++ goes right to left, clang left to right), and a scene
  // must not depend on the compiler. Second coordinate first: the scenes g++
  // has always made.
  const double dy = spread(rng);
  const double dx = spread(rng);
  const Eigen::Vector2d c = HeapCentre(placed) + Eigen::Vector2d(dx, dy);
  double radius = 0.0;
  for (const auto& p : placed) radius = std::max(radius, (p.translation().head<2>() - c).norm());
  const double phi = Uniform(rng, 0.0, 2 * std::numbers::pi);
  const double z = RestHeight(dims, R);
  const Eigen::Vector3d to(c.x(), c.y(), z);
  const Eigen::Vector3d from = to + (radius + 2.0 * dims.vec().norm() + 0.1) *
                                        Eigen::Vector3d(std::cos(phi), std::sin(phi), 0);
  return MakePose(R, MoveUntilContact(dims, R, from, to, placed));
}

// Drops a box from above (x, y) onto the heap or the floor.
Eigen::Isometry3d DropAt(const BoxDims& dims, const Eigen::Matrix3d& R, const Eigen::Vector2d& xy,
                         const std::vector<Eigen::Isometry3d>& placed) {
  const double reach = 0.5 * dims.vec().norm();
  double top = 0.0;
  for (const auto& p : placed) top = std::max(top, p.translation().z() + reach);
  const Eigen::Vector3d from(xy.x(), xy.y(), top + reach + 0.01);
  const Eigen::Vector3d to(xy.x(), xy.y(), RestHeight(dims, R));
  return MakePose(R, MoveUntilContact(dims, R, from, to, placed));
}

// Soft-min over drop spots and tilts: low resting centres are preferred,
// which is a crude stand-in for settling.
Eigen::Isometry3d DropOnHeap(const BoxDims& dims, const std::vector<Eigen::Isometry3d>& placed,
                             std::mt19937& rng) {
  const double size = std::max(dims.l, dims.b);
  std::normal_distribution<double> spread(0.0, 0.5 * size);
  std::vector<Eigen::Isometry3d> candidates;
  std::vector<double> weights;
  for (int c = 0; c < 6; ++c) {
    const Eigen::Isometry3d& anchor =
        placed[std::uniform_int_distribution<size_t>(0, placed.size() - 1)(rng)];
    const double dy = spread(rng);  // one at a time, as in SlideIn
    const double dx = spread(rng);
    const Eigen::Vector2d xy = anchor.translation().head<2>() + Eigen::Vector2d(dx, dy);
    const Eigen::Matrix3d flat = RandomOrientation(rng);
    Eigen::Matrix3d R = flat;
    if (Uniform(rng, 0.0, 1.0) < 0.7) {
      const double phi = Uniform(rng, 0.0, 2 * std::numbers::pi);
      R = Eigen::AngleAxisd(Uniform(rng, 5.0, 30.0) * kDeg,
                            Eigen::Vector3d(std::cos(phi), std::sin(phi), 0))
              .matrix() *
          flat;
    }
    Eigen::Isometry3d pose = DropAt(dims, R, xy, placed);
    // A tilted box that reached the floor would stand on an edge: lay it flat.
    const bool on_floor = pose.translation().z() - RestHeight(dims, R) < 1e-6;
    if (on_floor && !R.isApprox(flat)) pose = DropAt(dims, flat, xy, placed);
    candidates.push_back(pose);
  }
  double lowest = 1e9;
  for (const auto& p : candidates) lowest = std::min(lowest, p.translation().z());
  for (const auto& p : candidates)
    weights.push_back(std::exp(-(p.translation().z() - lowest) / 0.02));
  return candidates[std::discrete_distribution<size_t>(weights.begin(), weights.end())(rng)];
}

}  // namespace

Scene MakeIsolatedScene(const BoxDims& dims, int num_boxes, uint32_t seed,
                        const CameraPlacement& placement) {
  std::mt19937 rng(seed);
  const CameraRange range = Range(placement, 0.9, 1.3, 20.0);
  // 6 cm apart: each footprint grows by 3 cm on every side and must not overlap.
  const BoxDims padded{dims.l + 0.06, dims.b + 0.06, dims.h};
  Scene best;
  for (int attempt = 0; attempt < 200; ++attempt) {
    Scene scene;
    scene.camera = placement.intrinsics;
    scene.noise_seed = NoiseSeed(seed);
    // Move the camera back if the boxes keep failing to fit.
    const double extra = std::min(0.3, 0.01 * attempt);
    SetRandomCamera(Eigen::Vector3d::Zero(), range.lo + extra, range.hi + extra, range.tilt, rng,
                    &scene);
    const Eigen::Isometry3d& world_T_camera = scene.world_T_camera;
    const CameraIntrinsics& cam = scene.camera;
    for (int tries = 0; tries < 300 && static_cast<int>(scene.boxes.size()) < num_boxes; ++tries) {
      // Aim at a random pixel and put the box centre where that ray meets z = h/2.
      const double v = Uniform(rng, 0, cam.height);  // one at a time, as in SlideIn
      const double u = Uniform(rng, 0, cam.width);
      const Eigen::Vector3d ray_cam((u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy, 1.0);
      const Eigen::Vector3d ray = world_T_camera.linear() * ray_cam;
      const Eigen::Vector3d& origin = world_T_camera.translation();
      if (ray.z() > -1e-3) continue;
      const double t = (0.5 * dims.h - origin.z()) / ray.z();
      const Eigen::Isometry3d pose =
          MakePose(Yaw(Uniform(rng, 0.0, 2 * std::numbers::pi)), origin + t * ray);
      if (!FullyInView(scene, dims, pose, 3.0)) continue;
      bool apart = true;
      for (const SceneBox& other : scene.boxes) {
        if (ObbSeparation(padded, pose, padded, other.world_T_box) < 0.0) apart = false;
      }
      if (apart) scene.boxes.push_back({dims, pose, true});
    }
    if (scene.boxes.size() > best.boxes.size() || attempt == 0) best = scene;
    if (static_cast<int>(best.boxes.size()) >= num_boxes) break;
  }
  KeepBeyondNearRange(placement, &best);
  return best;
}

Scene MakeHeapScene(const BoxDims& dims, int num_boxes, uint32_t seed,
                    const CameraPlacement& placement) {
  std::mt19937 rng(seed);
  Scene scene;
  scene.camera = placement.intrinsics;
  scene.noise_seed = NoiseSeed(seed);
  std::vector<Eigen::Isometry3d> placed;
  for (int i = 0; i < num_boxes; ++i) {
    Eigen::Isometry3d pose;
    if (placed.empty()) {
      const Eigen::Matrix3d R = RandomOrientation(rng);
      pose = MakePose(R, Eigen::Vector3d(0, 0, RestHeight(dims, R)));
    } else if (Uniform(rng, 0.0, 1.0) < 0.5) {
      pose = SlideIn(dims, RandomOrientation(rng), placed, rng);
    } else {
      pose = DropOnHeap(dims, placed, rng);
    }
    if (!Free(dims, pose, placed)) continue;  // defensive: never interpenetrate
    placed.push_back(pose);
    scene.boxes.push_back({dims, pose, true});
  }
  const Eigen::Vector2d c = HeapCentre(placed);
  double mean_z = 0.0;
  for (const auto& p : placed) mean_z += p.translation().z() / placed.size();
  const CameraRange range = Range(placement, 1.0, 1.5, 25.0);
  SetRandomCamera(Eigen::Vector3d(c.x(), c.y(), mean_z), range.lo, range.hi, range.tilt, rng,
                  &scene);
  KeepBeyondNearRange(placement, &scene);
  return scene;
}

Scene MakeCellScene(const BoxDims& dims, int num_boxes, uint32_t seed) {
  Scene scene = MakeHeapScene(dims, num_boxes, seed);
  scene.world_T_camera =
      LookAtCamera(Eigen::Vector3d::Zero(), kCellCameraHeight, /*tilt_deg=*/0.0, /*yaw_deg=*/0.0,
                   /*roll_deg=*/0.0);
  return scene;
}

Scene MakePalletScene(const BoxDims& dims, int rows, int cols, int layers, double gap_m,
                      int removed_top, uint32_t seed, const CameraPlacement& placement) {
  return MakeDistractorPalletScene(dims, rows, cols, layers, gap_m, removed_top, 0, seed,
                                   placement);
}

Scene MakeDistractorPalletScene(const BoxDims& dims, int rows, int cols, int layers, double gap_m,
                                int removed_top, int num_distractors, uint32_t seed,
                                const CameraPlacement& placement) {
  std::mt19937 rng(seed);
  Scene scene;
  scene.camera = placement.intrinsics;
  scene.noise_seed = NoiseSeed(seed);
  scene.supports = MakeEurPallet(Eigen::Isometry3d::Identity());

  // Top-layer cells to remove: row by row from a random corner.
  const bool flip_r = Uniform(rng, 0, 1) < 0.5, flip_c = Uniform(rng, 0, 1) < 0.5;
  std::vector<bool> removed(rows * cols, false);
  for (int k = 0; k < std::min(removed_top, rows * cols); ++k) {
    const int r = k / cols, c = k % cols;
    removed[(flip_r ? rows - 1 - r : r) * cols + (flip_c ? cols - 1 - c : c)] = true;
  }

  std::vector<Eigen::Isometry3d> placed;
  std::vector<size_t> top_boxes;  // indices of the top layer's boxes
  for (int layer = 0; layer < layers; ++layer) {
    const double z = kEurPalletHeight + (layer + 0.5) * dims.h;
    for (int r = 0; r < rows; ++r) {
      for (int c = 0; c < cols; ++c) {
        if (layer == layers - 1 && removed[r * cols + c]) continue;
        const Eigen::Vector3d nominal((c - 0.5 * (cols - 1)) * (dims.l + gap_m),
                                      (r - 0.5 * (rows - 1)) * (dims.b + gap_m), z);
        const double dx = Uniform(rng, -2e-3, 2e-3), dy = Uniform(rng, -2e-3, 2e-3);
        const double yaw = Uniform(rng, -0.6, 0.6) * kDeg;
        // Cells fill towards +x and +y, so pushing a box that hits an earlier
        // neighbour that way frees it with the least drift.
        const Eigen::Vector3d push = Eigen::Vector3d(1, 1, 0).normalized();
        Eigen::Isometry3d pose = MakePose(Yaw(yaw), nominal + Eigen::Vector3d(dx, dy, 0));
        for (int k = 0; k < 200 && !Free(dims, pose, placed); ++k) {
          pose.translation() += 2e-4 * push;
        }
        if (!Free(dims, pose, placed)) continue;  // defensive: never interpenetrate
        placed.push_back(pose);
        scene.boxes.push_back({dims, pose, true});
        if (layer == layers - 1) top_boxes.push_back(scene.boxes.size() - 1);
      }
    }
  }
  const double top = kEurPalletHeight + layers * dims.h;
  const CameraRange range = Range(placement, 1.1, 1.5, 20.0);
  SetRandomCamera(Eigen::Vector3d(0, 0, top), range.lo, range.hi, range.tilt, rng, &scene);
  // Drawn after the camera, so scenes without distractors keep their streams.
  if (num_distractors > 0) {
    std::shuffle(top_boxes.begin(), top_boxes.end(), rng);
    for (int d = 0; d < num_distractors && d < static_cast<int>(top_boxes.size()); ++d) {
      SceneBox& box = scene.boxes[top_boxes[d]];
      const BoxDims other{dims.l * Uniform(rng, 0.55, 0.85), dims.b * Uniform(rng, 0.6, 0.9),
                          dims.h * Uniform(rng, 0.6, 1.3)};
      // Pushed against one corner of the cell, resting on the layer below.
      const double sx = Uniform(rng, 0, 1) < 0.5 ? -1 : 1, sy = Uniform(rng, 0, 1) < 0.5 ? -1 : 1;
      Eigen::Isometry3d pose = box.world_T_box;
      pose.translation() += pose.linear() * Eigen::Vector3d(sx * 0.5 * (dims.l - other.l),
                                                            sy * 0.5 * (dims.b - other.b), 0.0);
      pose.translation().z() += 0.5 * (other.h - dims.h);
      box = {other, pose, false};
    }
  }
  KeepBeyondNearRange(placement, &scene);
  return scene;
}

std::vector<SupportPart> MakeEurPallet(const Eigen::Isometry3d& world_T_pallet) {
  std::vector<SupportPart> parts;
  auto add = [&](const char* name, double l, double b, double h, double x, double y, double z0) {
    parts.push_back({name, {l, b, h}, world_T_pallet * Eigen::Translation3d(x, y, z0 + 0.5 * h)});
  };
  const double kBoard = 0.022;
  // Bottom boards, blocks, stringer boards across, then the top deck.
  const double ys[3] = {-0.35, 0.0, 0.35};
  const double yw[3] = {0.1, 0.145, 0.1};
  const double xs[3] = {-0.5275, 0.0, 0.5275};
  for (int j = 0; j < 3; ++j) add("bottom_board", 1.2, yw[j], kBoard, 0.0, ys[j], 0.0);
  for (double x : xs) {
    for (int j = 0; j < 3; ++j) add("block", 0.145, yw[j], 0.078, x, ys[j], kBoard);
    add("stringer_board", 0.145, 0.8, kBoard, x, 0.0, 0.1);
  }
  const double deck_y[5] = {-0.3275, -0.16375, 0.0, 0.16375, 0.3275};
  const double deck_w[5] = {0.145, 0.1, 0.145, 0.1, 0.145};
  for (int j = 0; j < 5; ++j) {
    add("deck_board", 1.2, deck_w[j], kBoard, 0.0, deck_y[j], kEurPalletHeight - kBoard);
  }
  return parts;
}

std::vector<SupportPart> MakeTable(const Eigen::Isometry3d& world_T_table, double length_m,
                                   double width_m, double height_m) {
  const double kTop = 0.03, kLeg = 0.05, kInset = 0.05;
  std::vector<SupportPart> parts;
  parts.push_back({"table_top",
                   {length_m, width_m, kTop},
                   world_T_table * Eigen::Translation3d(0, 0, height_m - 0.5 * kTop)});
  const double leg_h = height_m - kTop;
  for (int sx : {-1, 1}) {
    for (int sy : {-1, 1}) {
      parts.push_back(
          {"table_leg",
           {kLeg, kLeg, leg_h},
           world_T_table * Eigen::Translation3d(sx * (0.5 * length_m - kInset),
                                                sy * (0.5 * width_m - kInset), 0.5 * leg_h)});
    }
  }
  return parts;
}

}  // namespace cornerpose::testing
