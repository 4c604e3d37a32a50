// The generator's sensor models (active stereo, time of flight, the Kinect
// v1 model kept as it was) and its colour rendering: each model's statistics.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "tests/support/obb.h"
#include "tests/support/scene_generator.h"

namespace cornerpose::testing {
namespace {

constexpr BoxDims kCartonS{0.30, 0.20, 0.15};

SensorOptions Sensor(SensorKind kind, bool color = false) {
  SensorOptions s;
  s.kind = kind;
  s.color.enabled = color;
  return s;
}

// Boxes standing on the floor at the given world x, below a camera straight
// above the origin at camera_height.
Scene TopDown(SensorKind kind, double camera_height, const std::vector<double>& box_x,
              const BoxDims& dims = kCartonS) {
  Scene scene;
  scene.camera = *SensorIntrinsics(kind);
  scene.world_T_camera = LookAtCamera(Eigen::Vector3d::Zero(), camera_height, 0, 0, 0);
  for (double x : box_x) {
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.translation() = Eigen::Vector3d(x, 0, 0.5 * dims.h);
    scene.boxes.push_back({dims, pose, true});
  }
  return scene;
}

struct Moments {
  double mean = 0, stddev = 0;
  int count = 0;
};
// Depth statistics over the valid pixels the predicate selects.
template <typename Pred>
Moments DepthMoments(const RenderedScene& r, Pred pred) {
  double sum = 0, sq = 0;
  Moments m;
  for (size_t i = 0; i < r.cloud.size(); ++i) {
    const float z = r.cloud.xyz[i].z();
    if (!std::isfinite(z) || !pred(static_cast<int>(i))) continue;
    sum += z;
    sq += double(z) * z;
    ++m.count;
  }
  if (m.count == 0) return m;
  m.mean = sum / m.count;
  m.stddev = std::sqrt(std::max(0.0, sq / m.count - m.mean * m.mean));
  return m;
}

double Luma(uint32_t rgb) {
  return 0.2126 * ((rgb >> 16) & 0xFF) + 0.7152 * ((rgb >> 8) & 0xFF) + 0.0722 * (rgb & 0xFF);
}

uint64_t Fnv(uint64_t h, const void* data, size_t n) {
  const auto* b = static_cast<const unsigned char*>(data);
  for (size_t i = 0; i < n; ++i) h = (h ^ b[i]) * 1099511628211ull;
  return h;
}

uint64_t Checksum(const RenderedScene& r) {
  uint64_t h = 1469598103934665603ull;
  h = Fnv(h, r.cloud.xyz.data(), r.cloud.xyz.size() * sizeof(Eigen::Vector3f));
  h = Fnv(h, r.instance.data(), r.instance.size());
  return Fnv(h, r.face.data(), r.face.size());
}

// The Kinect v1 frames are those the generator made before the other sensor
// models existed (checksums computed with that version).
TEST(SensorModelsTest, KinectFramesUnchangedForFixedSeeds) {
  const BoxDims carton_l{0.40, 0.30, 0.25}, brick{0.19, 0.09, 0.057};
  const Scene scenes[] = {MakeIsolatedScene(kCartonS, 3, 5), MakeHeapScene(kCartonS, 10, 7),
                          MakePalletScene(carton_l, 2, 3, 2, 0.002, 2, 3),
                          MakePalletScene(brick, 4, 4, 2, 0.003, 3, 11),
                          MakeCellScene(kCartonS, 6, 2)};
  const uint64_t expected[] = {0x36c0ac563c4ff0d0ull, 0xe63d059b9323d2cdull, 0xf7b34ca74eb1dcf6ull,
                               0xdea3f66a74053b0dull, 0x54b624252e198b1aull};
  for (int k = 0; k < 5; ++k) {
    const RenderedScene r = Render(scenes[k]);
    EXPECT_EQ(Checksum(r), expected[k]) << "scene " << k;
    // Through the sensor interface, with colour on, the depth is the same.
    const RenderedScene c = Render(scenes[k], Sensor(SensorKind::kKinect, true));
    EXPECT_EQ(Checksum(c), expected[k]) << "scene " << k;
    EXPECT_EQ(c.cloud.rgb.size(), c.cloud.size());
    EXPECT_TRUE(r.cloud.rgb.empty());
  }
}

TEST(SensorModelsTest, StereoNoiseGrowsWithTheSquareOfDepth) {
  auto floor_sigma = [](double height) {
    const RenderedScene r =
        Render(TopDown(SensorKind::kStereo, height, {}), Sensor(SensorKind::kStereo));
    const Moments m = DepthMoments(r, [](int) { return true; });
    EXPECT_GT(m.count, 0.8 * r.cloud.size()) << height;
    EXPECT_NEAR(m.mean, height, 3e-3) << height;  // no bias
    return m.stddev;
  };
  const double near = floor_sigma(1.5), far = floor_sigma(2.4);
  // sigma_z = z^2 0.08 px / (607 px * 0.05 m): 5.9 mm at 1.5 m, 15.2 mm at 2.4 m.
  EXPECT_GT(near, 4.0e-3);
  EXPECT_LT(near, 8.0e-3);
  EXPECT_NEAR(far / near, (2.4 * 2.4) / (1.5 * 1.5), 0.4);
}

TEST(SensorModelsTest, StereoDropsDepthOutsideItsWorkingRange) {
  for (double height : {1.0, 2.7}) {
    const RenderedScene r =
        Render(TopDown(SensorKind::kStereo, height, {}), Sensor(SensorKind::kStereo));
    EXPECT_EQ(r.stats.valid, 0) << height;
  }
  const Scene scene =
      MakeHeapScene(kCartonS, 10, 4,
                    SensorPlacement(SensorKind::kStereo, *SensorIntrinsics(SensorKind::kStereo)));
  const RenderedScene r = Render(scene, Sensor(SensorKind::kStereo));
  EXPECT_GT(r.stats.valid, 0.5 * r.cloud.size());
  for (const Eigen::Vector3f& p : r.cloud.xyz) {
    if (!std::isfinite(p.z())) continue;
    ASSERT_GE(p.z(), 1.2f);
    ASSERT_LE(p.z(), 2.5f);
  }
}

// A cell puts its tallest box inside the camera's range: the stereo placement
// backs the camera off until every corner is 5 cm beyond the near end, so the
// top of a heap returns depth. The layout is the seed's either way; only the
// camera moves, along its axis.
TEST(SensorModelsTest, StereoPlacementKeepsEveryBoxBeyondTheNearRange) {
  const CameraIntrinsics k = *SensorIntrinsics(SensorKind::kStereo);
  const CameraPlacement stereo = SensorPlacement(SensorKind::kStereo, k);
  CameraPlacement unlimited = stereo;
  unlimited.min_depth_m = -1.0;
  int moved = 0;
  for (uint32_t seed = 1; seed <= 12; ++seed) {
    const Scene kept = MakeHeapScene(kCartonS, 13, seed, stereo);
    const Scene free = MakeHeapScene(kCartonS, 13, seed, unlimited);
    ASSERT_EQ(kept.boxes.size(), free.boxes.size());
    double nearest_kept = 1e9, nearest_free = 1e9;
    for (size_t i = 0; i < kept.boxes.size(); ++i) {
      EXPECT_TRUE(kept.boxes[i].world_T_box.isApprox(free.boxes[i].world_T_box));
      for (const Eigen::Vector3d& c : BoxCorners(
               kept.boxes[i].dims, kept.world_T_camera.inverse() * kept.boxes[i].world_T_box)) {
        nearest_kept = std::min(nearest_kept, c.z());
      }
      for (const Eigen::Vector3d& c : BoxCorners(
               free.boxes[i].dims, free.world_T_camera.inverse() * free.boxes[i].world_T_box)) {
        nearest_free = std::min(nearest_free, c.z());
      }
    }
    EXPECT_GE(nearest_kept, StereoOptions{}.min_range_m + 0.05 - 1e-9) << seed;
    EXPECT_TRUE(kept.world_T_camera.linear().isApprox(free.world_T_camera.linear()));
    if (nearest_free < stereo.min_depth_m) {
      ++moved;
      // Backed off along the optical axis by exactly the shortfall.
      const Eigen::Vector3d shift =
          free.world_T_camera.translation() - kept.world_T_camera.translation();
      EXPECT_NEAR(shift.dot(free.world_T_camera.linear().col(2)), stereo.min_depth_m - nearest_free,
                  1e-9);
    } else {
      EXPECT_TRUE(kept.world_T_camera.isApprox(free.world_T_camera)) << seed;
    }
  }
  EXPECT_GT(moved, 0);  // heaps of 13 cartons do reach into the near range
}

// Two cartons 2 mm apart: the crack between them shows the floor to exact
// rays, but not in stereo depth; in colour the seam is darker than the faces.
TEST(SensorModelsTest, StereoFillsTheSeamBetweenTouchingBoxesAndColourShowsIt) {
  const double gap = 0.002, height = 1.8;
  const Scene scene =
      TopDown(SensorKind::kStereo, height, {-0.5 * (kCartonS.l + gap), 0.5 * (kCartonS.l + gap)});
  const RenderedScene r = Render(scene, Sensor(SensorKind::kStereo, true));
  const CameraIntrinsics& cam = r.camera;
  const double z_top = height - kCartonS.h;
  int seam_px = 0, seam_valid = 0, seam_on_top = 0;
  double seam_luma = 0, face_luma = 0;
  int face_px = 0;
  for (int v = 0; v < cam.height; ++v) {
    for (int u = 1; u < cam.width; ++u) {
      const int i = v * cam.width + u;
      // Where the instance changes from box 1 to box 2 (or the floor between them).
      const bool seam = r.instance[i - 1] == 1 && r.instance[i] != 1 &&
                        (r.instance[i] == 2 || (u + 1 < cam.width && r.instance[i + 1] == 2));
      if (seam) {
        ++seam_px;
        const float z = r.cloud.xyz[i].z();
        if (std::isfinite(z)) {
          ++seam_valid;
          seam_on_top += std::abs(z - z_top) < 0.03;
        }
        seam_luma += Luma(r.cloud.rgb[i]) + Luma(r.cloud.rgb[i - 1]);
      }
      // Face pixels well inside box 1.
      if (u >= 12 && r.instance[i] == 1 && r.instance[i - 12] == 1 && u + 12 < cam.width &&
          r.instance[i + 12] == 1 && v >= 12 && v + 12 < cam.height &&
          r.instance[i - 12 * cam.width] == 1 && r.instance[i + 12 * cam.width] == 1) {
        face_luma += Luma(r.cloud.rgb[i]);
        ++face_px;
      }
    }
  }
  ASSERT_GT(seam_px, 50);
  ASSERT_GT(face_px, 1000);
  EXPECT_GT(seam_valid, 0.9 * seam_px);
  EXPECT_GT(seam_on_top, 0.9 * seam_valid);  // no depth signal at the seam
  EXPECT_GT(r.stats.filled, 0);
  EXPECT_LT(seam_luma / (2 * seam_px), 0.85 * face_luma / face_px);
}

TEST(SensorModelsTest, StereoInvalidBandLiesLeftOfAnOccluder) {
  const BoxDims tall{0.30, 0.20, 0.40};
  const Scene scene = TopDown(SensorKind::kStereo, 2.0, {0.0}, tall);
  const RenderedScene r = Render(scene, Sensor(SensorKind::kStereo));
  const CameraIntrinsics& cam = r.camera;
  // The top face spans u = cx -+ fx 0.15 / 1.6; count invalid floor pixels
  // in 12-px strips beside it, rows through the box's middle.
  const int left = static_cast<int>(cam.cx - cam.fx * 0.15 / 1.6);
  const int right = static_cast<int>(cam.cx + cam.fx * 0.15 / 1.6);
  int invalid_left = 0, invalid_right = 0;
  for (int v = static_cast<int>(cam.cy) - 30; v <= static_cast<int>(cam.cy) + 30; ++v) {
    for (int k = 1; k <= 12; ++k) {
      invalid_left += !std::isfinite(r.cloud.xyz[v * cam.width + left - k].z());
      invalid_right += !std::isfinite(r.cloud.xyz[v * cam.width + right + k].z());
    }
  }
  // Geometric band fx b dz / z^2 = 607 * 0.05 * 0.4 / (1.6 * 2.0) ~ 3.8 px, plus the margin.
  EXPECT_GT(invalid_left, 61 * 4);
  EXPECT_LT(invalid_right, 61);
  EXPECT_GT(r.stats.shadow, 0);
  // The left image border the right imager does not see: fx b / z ~ 15 px.
  for (int v = 0; v < cam.height; v += 7) {
    EXPECT_FALSE(std::isfinite(r.cloud.xyz[v * cam.width + 5].z())) << v;
  }
}

TEST(SensorModelsTest, StereoResolution1280x720) {
  Scene scene = TopDown(SensorKind::kStereo, 1.8, {0.0});
  scene.camera = *SensorIntrinsics(SensorKind::kStereo, 1280, 720);
  const RenderedScene r = Render(scene, Sensor(SensorKind::kStereo, true));
  EXPECT_EQ(r.cloud.width, 1280);
  EXPECT_EQ(r.cloud.height, 720);
  EXPECT_EQ(r.cloud.rgb.size(), 1280u * 720u);
  EXPECT_GT(r.stats.valid, 0.8 * r.cloud.size());
}

// Depth jumps in time of flight: pixels whose footprint straddles the box's
// outline return a depth between the top face and the floor.
TEST(SensorModelsTest, TimeOfFlightMixedPixelsAppearAtDepthJumps) {
  const double height = 1.3, z_top = height - kCartonS.h;
  const RenderedScene r =
      Render(TopDown(SensorKind::kTimeOfFlight, height, {0.0}), Sensor(SensorKind::kTimeOfFlight));
  const CameraIntrinsics& cam = r.camera;
  EXPECT_EQ(cam.width, 512);
  EXPECT_EQ(cam.height, 424);
  int between = 0, between_far_from_outline = 0;
  for (int v = 2; v < cam.height - 2; ++v) {
    for (int u = 2; u < cam.width - 2; ++u) {
      const float z = r.cloud.xyz[v * cam.width + u].z();
      if (!std::isfinite(z) || z < z_top + 0.02 || z > height - 0.025) continue;
      ++between;
      bool near_outline = false;
      for (int dv = -1; dv <= 1; ++dv) {
        for (int du = -1; du <= 1; ++du) {
          near_outline |=
              r.instance[(v + dv) * cam.width + u + du] != r.instance[v * cam.width + u];
        }
      }
      between_far_from_outline += !near_outline;
    }
  }
  EXPECT_GT(between, 30);
  // Away from the outline only the rare far tail of the noise gets there.
  EXPECT_LT(between_far_from_outline, 0.05 * between);
  EXPECT_GT(r.stats.flying, 30);
}

// Where a box's side meets the floor (a concave crease), light from the
// floor reaches the side and the side reads farther than it is.
TEST(SensorModelsTest, TimeOfFlightMultipathBiasesConcaveCreases) {
  const double height = 1.3;
  const BoxDims tall{0.30, 0.20, 0.30};
  // Off centre, so the camera sees the box's -x side and the floor before it.
  const Scene scene = TopDown(SensorKind::kTimeOfFlight, height, {0.35}, tall);
  const RenderedScene r = Render(scene, Sensor(SensorKind::kTimeOfFlight));
  NoiseOptions exact;
  exact.enabled = false;
  const RenderedScene e = Render(scene, exact);
  double crease = 0, open = 0;
  int n_crease = 0, n_open = 0;
  for (size_t i = 0; i < r.cloud.size(); ++i) {
    const float z = r.cloud.xyz[i].z(), z_exact = e.cloud.xyz[i].z();
    if (!std::isfinite(z) || !std::isfinite(z_exact)) continue;
    const double above_floor = height - z_exact, x = e.cloud.xyz[i].x();
    if (r.instance[i] == 1 && r.face[i] == 1 + static_cast<int>(BoxFace::kMinusX) &&
        above_floor < 0.05) {
      crease += z - z_exact;
      ++n_crease;
    } else if (r.instance[i] == 0 && x < -0.1) {
      open += z - z_exact;
      ++n_open;
    }
  }
  ASSERT_GT(n_crease, 30);
  ASSERT_GT(n_open, 5000);
  EXPECT_NEAR(open / n_open, 0.0, 1e-3);
  EXPECT_GT(crease / n_crease - open / n_open, 4e-3);
  EXPECT_GT(r.stats.multipath, 0);
}

TEST(SensorModelsTest, TimeOfFlightNoiseGrowsAsTheReturnWeakens) {
  auto floor_sigma = [](double height) {
    const RenderedScene r =
        Render(TopDown(SensorKind::kTimeOfFlight, height, {}), Sensor(SensorKind::kTimeOfFlight));
    return DepthMoments(r, [](int) { return true; }).stddev;
  };
  // The amplitude falls as 1/z^2, so sigma grows about as z.
  const double near = floor_sigma(1.0), far = floor_sigma(3.0);
  EXPECT_GT(near, 1.0e-3);
  EXPECT_LT(near, 10e-3);
  EXPECT_GT(far / near, 2.0);
  EXPECT_LT(far / near, 4.5);
  for (double height : {0.4, 4.8}) {
    EXPECT_EQ(
        Render(TopDown(SensorKind::kTimeOfFlight, height, {}), Sensor(SensorKind::kTimeOfFlight))
            .stats.valid,
        0)
        << height;
  }
}

TEST(SensorModelsTest, TimeOfFlightColourIsGreyInfrared) {
  const RenderedScene r = Render(TopDown(SensorKind::kTimeOfFlight, 1.3, {0.0}),
                                 Sensor(SensorKind::kTimeOfFlight, true));
  ASSERT_EQ(r.cloud.rgb.size(), r.cloud.size());
  double box = 0, floor = 0;
  int nb = 0, nf = 0;
  for (size_t i = 0; i < r.cloud.size(); ++i) {
    const uint32_t c = r.cloud.rgb[i];
    ASSERT_EQ((c >> 16) & 0xFF, c & 0xFF);
    ASSERT_EQ((c >> 8) & 0xFF, c & 0xFF);
    (r.instance[i] == 1 ? box : floor) += c & 0xFF;
    ++(r.instance[i] == 1 ? nb : nf);
  }
  // Cardboard nearer the illuminator returns more light than the concrete floor.
  EXPECT_GT(box / nb, 1.1 * floor / nf);
}

TEST(SensorModelsTest, SameSeedSameFramesForEverySensor) {
  for (SensorKind kind : {SensorKind::kStereo, SensorKind::kTimeOfFlight}) {
    const CameraPlacement place = SensorPlacement(kind, *SensorIntrinsics(kind));
    Scene scene = MakeDistractorPalletScene(kCartonS, 3, 3, 2, 0.001, 3, 2, 9, place);
    const RenderedScene a = Render(scene, Sensor(kind, true));
    const RenderedScene b = Render(
        MakeDistractorPalletScene(kCartonS, 3, 3, 2, 0.001, 3, 2, 9, place), Sensor(kind, true));
    EXPECT_EQ(Checksum(a), Checksum(b)) << SensorKindName(kind);
    EXPECT_EQ(a.cloud.rgb, b.cloud.rgb) << SensorKindName(kind);
    scene.noise_seed += 1;
    const RenderedScene c = Render(scene, Sensor(kind, true));
    EXPECT_EQ(a.instance, c.instance);
    EXPECT_NE(Checksum(a), Checksum(c)) << SensorKindName(kind);
  }
}

TEST(SensorModelsTest, DistractorPalletReplacesTopLayerBoxes) {
  const Scene plain = MakePalletScene(kCartonS, 3, 4, 2, 0.001, 3, 21);
  const Scene same = MakeDistractorPalletScene(kCartonS, 3, 4, 2, 0.001, 3, 0, 21);
  ASSERT_EQ(plain.boxes.size(), same.boxes.size());
  for (size_t i = 0; i < plain.boxes.size(); ++i) {
    EXPECT_TRUE(plain.boxes[i].world_T_box.isApprox(same.boxes[i].world_T_box));
  }
  EXPECT_TRUE(plain.world_T_camera.isApprox(same.world_T_camera));
  const Scene mixed = MakeDistractorPalletScene(kCartonS, 3, 4, 2, 0.001, 3, 3, 21);
  ASSERT_EQ(mixed.boxes.size(), plain.boxes.size());
  int distractors = 0;
  for (size_t i = 0; i < mixed.boxes.size(); ++i) {
    const SceneBox& b = mixed.boxes[i];
    if (b.target) continue;
    ++distractors;
    EXPECT_LT(b.dims.l, kCartonS.l);
    EXPECT_LT(b.dims.b, kCartonS.b);
    // On the layer below: its bottom at the pallet deck plus one layer.
    EXPECT_NEAR(b.world_T_box.translation().z() - 0.5 * b.dims.h, kEurPalletHeight + kCartonS.h,
                1e-9);
    for (size_t j = 0; j < mixed.boxes.size(); ++j) {
      if (j == i) continue;
      const SceneBox& o = mixed.boxes[j];
      EXPECT_GE(ObbSeparation(b.dims, b.world_T_box, o.dims, o.world_T_box), -1e-6);
    }
  }
  EXPECT_EQ(distractors, 3);
}

TEST(SensorModelsTest, OptionsAndResolutionsAreValidated) {
  EXPECT_TRUE(SensorOptions{}.Validate().ok());
  SensorOptions s = Sensor(SensorKind::kStereo, true);
  EXPECT_TRUE(s.Validate().ok());
  s.stereo.baseline_m = 0.0;
  absl::Status status = s.Validate();
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(status.message().find("baseline_m"), std::string::npos) << status;
  s = Sensor(SensorKind::kTimeOfFlight);
  s.tof.max_range_m = 0.2;  // below min_range_m
  EXPECT_NE(s.Validate().message().find("max_range_m"), std::string::npos);
  s = Sensor(SensorKind::kKinect, true);
  s.color.shadow_samples = 0;
  EXPECT_NE(s.Validate().message().find("shadow_samples"), std::string::npos);

  EXPECT_EQ(SensorIntrinsics(SensorKind::kTimeOfFlight, 640, 576)->fx, 505.0);
  EXPECT_EQ(SensorIntrinsics(SensorKind::kStereo)->fx, 607.0);
  EXPECT_EQ(SensorIntrinsics(SensorKind::kKinect)->fx, 525.0);
  const auto bad = SensorIntrinsics(SensorKind::kStereo, 512, 424);
  EXPECT_EQ(bad.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(bad.status().message().find("1280x720"), std::string::npos);
  EXPECT_EQ(*ParseSensorKind("tof"), SensorKind::kTimeOfFlight);
  EXPECT_FALSE(ParseSensorKind("lidar").ok());
}

}  // namespace
}  // namespace cornerpose::testing
