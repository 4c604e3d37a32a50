#include "tests/support/scene_generator.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <numbers>

#include "tests/support/obb.h"

namespace cornerpose::testing {
namespace {

constexpr BoxDims kCartonS{0.30, 0.20, 0.15};

NoiseOptions NoNoise() {
  NoiseOptions noise;
  noise.enabled = false;
  return noise;
}

// Only the projector shadow: everything else off.
NoiseOptions ShadowOnly() {
  NoiseOptions noise;
  noise.lateral_sigma_px = 0.0;
  noise.grazing_dropout = false;
  noise.flying_prob = 0.0;
  noise.axial_noise = false;
  noise.quantize = false;
  noise.output_step_m = 0.0;
  noise.dropout_prob = 0.0;
  noise.num_blobs = 0;
  return noise;
}

// A camera straight above the world origin, and boxes standing on the floor
// centred below it.
Scene TopDownScene(double camera_height, const std::vector<BoxDims>& boxes) {
  Scene scene;
  scene.world_T_camera = LookAtCamera(Eigen::Vector3d::Zero(), camera_height, 0, 0, 0);
  for (const BoxDims& dims : boxes) {
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.translation() = Eigen::Vector3d(0, 0, 0.5 * dims.h);
    scene.boxes.push_back({dims, pose, true});
  }
  return scene;
}

void ExpectNoInterpenetration(const Scene& scene) {
  for (size_t i = 0; i < scene.boxes.size(); ++i) {
    const SceneBox& a = scene.boxes[i];
    for (const Eigen::Vector3d& c : BoxCorners(a.dims, a.world_T_box)) EXPECT_GE(c.z(), -1e-6);
    for (size_t j = i + 1; j < scene.boxes.size(); ++j) {
      const SceneBox& b = scene.boxes[j];
      EXPECT_GE(ObbSeparation(a.dims, a.world_T_box, b.dims, b.world_T_box), -1e-6)
          << "boxes " << i << " and " << j;
    }
  }
}

TEST(SceneGeneratorTest, LookAtCameraSeesTheTargetOnItsAxis) {
  const Eigen::Vector3d target(0.3, -0.2, 0.1);
  const Eigen::Isometry3d world_T_camera = LookAtCamera(target, 1.3, 17.0, 40.0, 2.0);
  EXPECT_TRUE((world_T_camera.inverse() * target).isApprox(Eigen::Vector3d(0, 0, 1.3), 1e-12));
  // 17 deg from straight down.
  const double cos_tilt = -world_T_camera.linear().col(2).z();
  EXPECT_NEAR(std::acos(cos_tilt) * 180.0 / std::numbers::pi, 17.0, 1e-9);
}

TEST(SceneGeneratorTest, NoiseFreeTopDownBoxIsExact) {
  const double kHeight = 1.2;
  const Scene scene = TopDownScene(kHeight, {kCartonS});
  const RenderedScene out = Render(scene, NoNoise());
  const CameraIntrinsics& cam = out.camera;
  ASSERT_EQ(out.cloud.width, 640);
  ASSERT_EQ(out.cloud.height, 480);
  const double z_top = kHeight - kCartonS.h;

  int top_px = 0;
  for (int v = 0; v < cam.height; ++v) {
    for (int u = 0; u < cam.width; ++u) {
      const int i = v * cam.width + u;
      const Eigen::Vector3f& p = out.cloud.xyz[i];
      ASSERT_TRUE(PointCloud::IsValid(p));
      // Seen from straight above, only the top face shows, as this rectangle.
      const double x = (u - cam.cx) * z_top / cam.fx, y = (v - cam.cy) * z_top / cam.fy;
      const bool on_top = std::abs(x) < 0.5 * kCartonS.l && std::abs(y) < 0.5 * kCartonS.b;
      ASSERT_EQ(out.instance[i], on_top ? 1 : 0) << u << "," << v;
      if (on_top) {
        ++top_px;
        EXPECT_EQ(out.face[i], 1 + static_cast<int>(BoxFace::kPlusZ));
        EXPECT_NEAR(p.z(), z_top, 1e-6);
      } else {
        EXPECT_EQ(out.face[i], 0);
        EXPECT_NEAR(p.z(), kHeight, 1e-6);
        EXPECT_NEAR(out.floor_plane_camera.dot(p.cast<double>().homogeneous()), 0.0, 1e-6);
      }
    }
  }
  const double analytic = kCartonS.l * kCartonS.b * cam.fx * cam.fy / (z_top * z_top);
  EXPECT_NEAR(top_px, analytic, 0.01 * analytic);

  ASSERT_EQ(out.boxes.size(), 1u);
  const GroundTruthBox& gt = out.boxes[0];
  EXPECT_EQ(gt.px_visible, top_px);
  EXPECT_EQ(gt.px_unoccluded, top_px);
  EXPECT_DOUBLE_EQ(gt.visib_fract, 1.0);
  EXPECT_EQ(gt.grasp_face, BoxFace::kPlusZ);
  EXPECT_EQ(gt.grasp_px_visible, top_px);
  EXPECT_TRUE(gt.pickable);
  EXPECT_TRUE(
      gt.camera_T_box.translation().isApprox(Eigen::Vector3d(0, 0, kHeight - 0.075), 1e-12));
}

TEST(SceneGeneratorTest, BoxCutByTheBorderCountsUnoccludedBeyondTheImage) {
  Scene scene = TopDownScene(1.2, {kCartonS});
  // Half the box lies beyond the right image border.
  const double x_border = (639.5 - 319.5) * (1.2 - kCartonS.h) / 525.0;
  scene.boxes[0].world_T_box.translation().x() = x_border;
  const RenderedScene out = Render(scene, NoNoise());
  const GroundTruthBox& gt = out.boxes[0];
  // Half the top face is cut off; the side turned to the centre stays whole.
  EXPECT_EQ(gt.grasp_face, BoxFace::kPlusZ);
  EXPECT_NEAR(static_cast<double>(gt.grasp_px_visible) / gt.grasp_px_unoccluded, 0.5, 0.01);
  EXPECT_LT(gt.visib_fract, 0.75);
  EXPECT_FALSE(gt.pickable);
}

TEST(SceneGeneratorTest, FloorNoiseMatchesTheKinectModel) {
  const Scene scene = TopDownScene(1.2, {});
  const RenderedScene out = Render(scene, NoiseOptions{});
  double sum = 0.0, sq = 0.0;
  int count = 0;
  for (const Eigen::Vector3f& p : out.cloud.xyz) {
    if (!PointCloud::IsValid(p)) continue;
    sum += p.z();
    sq += p.z() * p.z();
    ++count;
  }
  ASSERT_GT(count, 0.95 * out.cloud.size());
  const double mean = sum / count;
  const double stddev = std::sqrt(sq / count - mean * mean);
  EXPECT_NEAR(mean, 1.2, 1e-3);
  EXPECT_GT(stddev, 1.5e-3);
  EXPECT_LT(stddev, 4.0e-3);
  // Depth comes out in whole millimetres.
  for (int i = 0; i < 1000; ++i) {
    const float z = out.cloud.xyz[i * 300].z();
    if (std::isfinite(z)) {
      EXPECT_NEAR(z * 1000.0, std::round(z * 1000.0), 1e-3);
    }
  }
}

TEST(SceneGeneratorTest, ProjectorShadowFallsLeftOfARaisedBox) {
  const BoxDims tall{0.30, 0.20, 0.30};
  const RenderedScene out = Render(TopDownScene(1.2, {tall}), ShadowOnly());
  const CameraIntrinsics& cam = out.camera;
  // The top spans u in [232, 407]; the floor beyond it from 1.2 m: the
  // projector 7.5 cm to the right is blocked for floor x in [-0.225, -0.2] m,
  // u in [221, 232), and never on the right side.
  for (int v = 230; v <= 250; ++v) {
    for (int u = 223; u <= 230; ++u) {
      EXPECT_FALSE(PointCloud::IsValid(out.cloud.xyz[v * cam.width + u])) << u << "," << v;
    }
    for (int u = 408; u <= 420; ++u) {
      EXPECT_TRUE(PointCloud::IsValid(out.cloud.xyz[v * cam.width + u])) << u << "," << v;
    }
  }
  int left = 0, right = 0;
  for (int i = 0; i < static_cast<int>(out.cloud.size()); ++i) {
    if (!PointCloud::IsValid(out.cloud.xyz[i])) ++((i % cam.width) < cam.cx ? left : right);
  }
  EXPECT_GT(left, 1000);
  EXPECT_EQ(right, 0);
  EXPECT_EQ(out.stats.shadow, left);
}

TEST(SceneGeneratorTest, SameSeedSameCloud) {
  Scene scene = MakeHeapScene(kCartonS, 8, 7);
  const RenderedScene a = Render(scene, NoiseOptions{});
  const RenderedScene b = Render(MakeHeapScene(kCartonS, 8, 7), NoiseOptions{});
  ASSERT_EQ(a.cloud.size(), b.cloud.size());
  EXPECT_EQ(
      std::memcmp(a.cloud.xyz.data(), b.cloud.xyz.data(), a.cloud.size() * sizeof(Eigen::Vector3f)),
      0);
  EXPECT_EQ(a.instance, b.instance);
  scene.noise_seed += 1;
  const RenderedScene c = Render(scene, NoiseOptions{});
  EXPECT_EQ(a.instance, c.instance);
  EXPECT_NE(
      std::memcmp(a.cloud.xyz.data(), c.cloud.xyz.data(), a.cloud.size() * sizeof(Eigen::Vector3f)),
      0);
}

TEST(SceneGeneratorTest, HeapBoxesTouchAndStackWithoutInterpenetrating) {
  for (uint32_t seed = 1; seed <= 6; ++seed) {
    const Scene scene = MakeHeapScene(kCartonS, 12, seed);
    ASSERT_EQ(scene.boxes.size(), 12u) << "seed " << seed;
    ExpectNoInterpenetration(scene);
    int touching = 0, raised = 0;
    for (size_t i = 0; i < scene.boxes.size(); ++i) {
      const SceneBox& a = scene.boxes[i];
      double lowest = 1e9;
      for (const Eigen::Vector3d& c : BoxCorners(a.dims, a.world_T_box))
        lowest = std::min(lowest, c.z());
      if (lowest > 0.01) ++raised;
      for (size_t j = i + 1; j < scene.boxes.size(); ++j) {
        const SceneBox& b = scene.boxes[j];
        if (ObbSeparation(a.dims, a.world_T_box, b.dims, b.world_T_box) < 1e-3) ++touching;
      }
    }
    EXPECT_GE(touching, 6) << "seed " << seed;
    EXPECT_GE(raised, 1) << "seed " << seed;
  }
}

TEST(SceneGeneratorTest, IsolatedBoxesAreAllPickable) {
  for (uint32_t seed = 1; seed <= 6; ++seed) {
    const Scene scene = MakeIsolatedScene(kCartonS, 3, seed);
    ASSERT_EQ(scene.boxes.size(), 3u) << "seed " << seed;
    ExpectNoInterpenetration(scene);
    const double distance = scene.world_T_camera.translation().norm();
    EXPECT_GT(distance, 0.85);
    EXPECT_LT(distance, 1.65);
    const RenderedScene out = Render(scene, NoiseOptions{});
    for (const GroundTruthBox& gt : out.boxes) {
      EXPECT_TRUE(gt.pickable) << "seed " << seed;
      EXPECT_EQ(gt.grasp_face, BoxFace::kPlusZ);
      EXPECT_GT(gt.visib_fract, 0.9);
    }
  }
}

TEST(SceneGeneratorTest, PalletGridWithRemovedTopBoxes) {
  const BoxDims carton_l{0.40, 0.30, 0.25};
  const Scene scene = MakePalletScene(carton_l, 2, 3, 2, 0.002, 2, 3);
  EXPECT_EQ(scene.boxes.size(), 10u);
  EXPECT_FALSE(scene.supports.empty());
  ExpectNoInterpenetration(scene);
  const RenderedScene out = Render(scene, NoiseOptions{});
  int pickable = 0;
  for (const GroundTruthBox& gt : out.boxes) pickable += gt.pickable;
  EXPECT_GE(pickable, 1);
  int support_px = 0;
  for (uint8_t label : out.instance) support_px += label == 255;
  EXPECT_GT(support_px, 0);
}

// Speed is not asserted here (machines are noisy); the time is printed for
// the record.
TEST(SceneGeneratorTest, HeapOfFifteenRendersMostPixels) {
  const Scene scene = MakeHeapScene(kCartonS, 15, 11);
  const auto start = std::chrono::steady_clock::now();
  const RenderedScene out = Render(scene, NoiseOptions{});
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  std::printf("15-box heap render: %.1f ms, %d valid px\n", ms, out.stats.valid);
  EXPECT_EQ(out.boxes.size(), 15u);
  EXPECT_GT(out.stats.valid, 0.5 * out.cloud.size());
}

}  // namespace
}  // namespace cornerpose::testing
