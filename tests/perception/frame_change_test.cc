#include "common/perception/frame_change.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <iostream>
#include <limits>
#include <string>

#include "common/perception/detector.h"
#include "common/perception/pose_error.h"
#include "tests/support/scene_generator.h"
#include "tests/support/scene_kinds.h"
#include "tests/support/sensor_options.h"

namespace cornerpose {
namespace {

using testing::CameraPlacement;
using testing::MakeSceneOfKind;
using testing::RenderedScene;
using testing::Scene;
using testing::SensorKind;
using testing::SensorOptions;

constexpr BoxDims kCarton{0.3, 0.2, 0.15};

struct Sensor {
  const char* name;
  SensorKind kind;
};
constexpr Sensor kSensors[] = {{"kinect", SensorKind::kKinect},
                               {"tof", SensorKind::kTimeOfFlight},
                               {"stereo", SensorKind::kStereo}};

// Scene `i` of `kind` for the sensor, as make_frames draws it.
Scene SceneFor(SensorKind sensor, const std::string& kind, int i, uint32_t seed,
               const BoxDims& dims = kCarton) {
  absl::StatusOr<CameraIntrinsics> k = testing::SensorIntrinsics(sensor);
  EXPECT_TRUE(k.ok());
  const CameraPlacement place = testing::SensorPlacement(sensor, *k);
  std::string type;
  absl::StatusOr<Scene> scene = MakeSceneOfKind(kind, dims, i, seed, place, &type);
  EXPECT_TRUE(scene.ok()) << scene.status();
  return *scene;
}

RenderedScene RenderWith(SensorKind sensor, const Scene& scene) {
  SensorOptions options;
  options.kind = sensor;
  return testing::Render(scene, options);
}

// The comparison as a stream makes it: windows the size of the box's
// smallest side.
FrameChangeOptions ForBox(const BoxDims& dims, const Scene& scene) {
  FrameChangeOptions o;
  o.box_side_m = std::min({dims.l, dims.b, dims.h});
  o.focal_px = scene.camera.fx;
  return o;
}

// The same scene again, with new sensor noise (its look kept).
Scene Again(Scene scene) {
  scene.look_seed = scene.LookSeed();
  scene.noise_seed += 1000;
  return scene;
}

// The box whose top is highest in the world (the one a cell takes next).
size_t Highest(const Scene& scene) {
  size_t best = 0;
  for (size_t i = 1; i < scene.boxes.size(); ++i) {
    if (scene.boxes[i].world_T_box.translation().z() >
        scene.boxes[best].world_T_box.translation().z()) {
      best = i;
    }
  }
  return best;
}

TEST(FrameChangeTest, OptionsOutOfRangeNameTheField) {
  FrameChangeOptions o;
  EXPECT_TRUE(o.Validate().ok());
  o.block_px = 1;
  EXPECT_NE(o.Validate().message().find("frame_change.block_px"), std::string::npos);
  o = {};
  o.max_valid_share_change = 1.5;
  EXPECT_NE(o.Validate().message().find("frame_change.max_valid_share_change"), std::string::npos);
  o = {};
  o.min_depth_change_m = 0.0;
  o.depth_change_per_m2 = 0.0;
  EXPECT_FALSE(o.Validate().ok());
  PointCloud c;
  EXPECT_EQ(CompareFrames(c, c, o).status().code(), absl::StatusCode::kInvalidArgument);
}

TEST(FrameChangeTest, CloudsWithoutPixelsToCompareAreNotTheSameScene) {
  PointCloud a;
  a.width = 4;
  a.height = 1;
  a.xyz.assign(4, Eigen::Vector3f(0, 0, 1));
  absl::StatusOr<FrameChange> unorganized = CompareFrames(a, a);
  ASSERT_TRUE(unorganized.ok());
  EXPECT_FALSE(unorganized->same_scene);
  PointCloud b;
  b.width = 16;
  b.height = 16;
  b.xyz.assign(256, Eigen::Vector3f(0, 0, 1));
  PointCloud c = b;
  c.width = 32;
  c.height = 8;
  absl::StatusOr<FrameChange> other_size = CompareFrames(b, c);
  ASSERT_TRUE(other_size.ok());
  EXPECT_FALSE(other_size->same_scene);
  absl::StatusOr<FrameChange> itself = CompareFrames(b, b);
  ASSERT_TRUE(itself.ok());
  EXPECT_TRUE(itself->same_scene);
  EXPECT_EQ(itself->compared_blocks, 4);
  EXPECT_EQ(itself->changed_blocks, 0);
}

// NaN, infinite, negative and absurd depths are no return: the sums stay
// finite, and a block that lost its returns to them has changed.
TEST(FrameChangeTest, BadDepthsAreNoReturn) {
  PointCloud a;
  a.width = 64;
  a.height = 64;
  a.xyz.assign(64 * 64, Eigen::Vector3f(0, 0, 1.5f));
  PointCloud b = a;
  const float bad[] = {std::numeric_limits<float>::quiet_NaN(),
                       std::numeric_limits<float>::infinity(), -1.0f, 1e30f};
  for (int y = 0; y < 32; ++y) {
    for (int x = 0; x < 32; ++x) b.xyz[y * 64 + x].z() = bad[(x + y) % 4];
  }
  FrameChangeOptions o;
  o.max_changed_blocks = 0;
  absl::StatusOr<FrameChange> change = CompareFrames(a, b, o);
  ASSERT_TRUE(change.ok());
  EXPECT_FALSE(change->same_scene);
  EXPECT_EQ(change->compared_blocks, 64);
  absl::StatusOr<FrameChange> itself = CompareFrames(b, b, o);
  ASSERT_TRUE(itself.ok());
  EXPECT_TRUE(itself->same_scene);
  EXPECT_EQ(itself->compared_blocks, 48);  // the bad quarter has no returns
}

// A carton or a brick taken away is a change on every sensor model, in
// heaps and in pallets of touching boxes; new sensor noise on the same scene
// mostly is not (a frame judged changed only costs a detection; one judged
// the same when it is not would carry boxes that are gone).
TEST(FrameChangeTest, ATakenBoxIsAChangeAndNoiseMostlyIsNot) {
  constexpr BoxDims kBrick{0.19, 0.09, 0.057};
  for (const Sensor& sensor : kSensors) {
    int same = 0, pairs = 0, least_taken = 1 << 30;
    for (const BoxDims& dims : {kCarton, kBrick}) {
      for (const std::string kind : {"touching", "heap"}) {
        for (int i = 0; i < 3; ++i) {
          SCOPED_TRACE(::testing::Message()
                       << sensor.name << " " << kind << " " << i << " box " << dims.l);
          const Scene scene = SceneFor(sensor.kind, kind, i, 170 + i, dims);
          const FrameChangeOptions o = ForBox(dims, scene);
          const PointCloud before = RenderWith(sensor.kind, scene).cloud;
          const Scene again = Again(scene);
          absl::StatusOr<FrameChange> noise =
              CompareFrames(before, RenderWith(sensor.kind, again).cloud, o);
          ASSERT_TRUE(noise.ok());
          EXPECT_GT(noise->compared_blocks, 1000);
          same += noise->same_scene;
          ++pairs;
          Scene taken = again;
          taken.boxes.erase(taken.boxes.begin() + Highest(taken));
          absl::StatusOr<FrameChange> t =
              CompareFrames(before, RenderWith(sensor.kind, taken).cloud, o);
          ASSERT_TRUE(t.ok());
          EXPECT_FALSE(t->same_scene) << t->changed_blocks << " blocks changed";
          least_taken = std::min(least_taken, t->changed_blocks);
        }
      }
    }
    std::cout << sensor.name << ": new noise the same scene in " << same << " of " << pairs
              << "; a box taken changes at least " << least_taken << " blocks\n";
    // Measured: kinect 12/12, tof 12/12, stereo 8/12 (far bricks: their
    // windows are small and the stereo error at 2.5 m large).
    EXPECT_GE(same, sensor.kind == SensorKind::kStereo ? pairs / 2 : pairs - 1);
    EXPECT_GE(least_taken, 2 * FrameChangeOptions{}.max_changed_blocks);
  }
}

// Boxes of `det` within 20 mm / 10 degrees of a target box of the scene.
int Correct(const RenderedScene& r, const Detection& det) {
  return static_cast<int>(
      std::count_if(det.boxes.begin(), det.boxes.end(), [&](const DetectedBox& b) {
        return std::any_of(r.boxes.begin(), r.boxes.end(), [&](const testing::GroundTruthBox& g) {
          const PoseError e = ComparePoses(b.camera_T_box, g.camera_T_box, kCarton);
          return g.target && e.translation_m < 0.02 && e.rotation_deg < 10.0;
        });
      }));
}

// What a stream carries to a frame of the same scene is as right as
// detecting on that frame: as many right boxes and no more wrong ones, over
// twelve pallets, within what the detector itself finds differently from
// one frame's noise to the next's (on a pallet of touching cartons a
// marginal box comes and goes: two detections of the same scene differ by
// up to three boxes here).
TEST(FrameChangeTest, CarriedBoxesAreAsRightAsAFullDetection) {
  int frames = 0, carried_boxes = 0, carried_correct = 0, full_boxes = 0, full_correct = 0;
  for (const Sensor& sensor : kSensors) {
    for (int i = 0; i < 4; ++i) {
      SCOPED_TRACE(::testing::Message() << sensor.name << " frame " << i);
      const Scene scene = SceneFor(sensor.kind, "touching", i, 90 + i);
      const RenderedScene first = RenderWith(sensor.kind, scene);
      const RenderedScene second = RenderWith(sensor.kind, Again(scene));
      absl::StatusOr<FrameChange> change =
          CompareFrames(first.cloud, second.cloud, ForBox(kCarton, scene));
      ASSERT_TRUE(change.ok());
      if (!change->same_scene) continue;  // a stream would detect again
      DetectorOptions options;
      options.box = kCarton;
      absl::StatusOr<Detection> carried = DetectBoxes(first.cloud, options);
      absl::StatusOr<Detection> full = DetectBoxes(second.cloud, options);
      ASSERT_TRUE(carried.ok());
      ASSERT_TRUE(full.ok());
      ++frames;
      // Judged against the second frame's ground truth: the scene's.
      const int c = Correct(second, *carried), f = Correct(second, *full);
      carried_boxes += static_cast<int>(carried->boxes.size());
      carried_correct += c;
      full_boxes += static_cast<int>(full->boxes.size());
      full_correct += f;
    }
  }
  std::cout << frames << " of 12 frames carried: carried " << carried_correct << "/"
            << carried_boxes << " right, detected again " << full_correct << "/" << full_boxes
            << " right\n";
  // Measured: 12 of 12 carried, 41/42 right against 48/50 right.
  EXPECT_GE(frames, 9);
  EXPECT_GT(carried_correct, 3 * frames);
  EXPECT_GE(carried_correct, 0.8 * full_correct);
  EXPECT_LE(carried_boxes - carried_correct, full_boxes - full_correct + 1);
}

}  // namespace
}  // namespace cornerpose
