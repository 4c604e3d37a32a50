#include "common/perception/box_evidence.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <numbers>
#include <tuple>
#include <vector>

#include "tests/support/scene_generator.h"

namespace cornerpose::testing {
namespace {

constexpr BoxDims kCartonS{0.30, 0.20, 0.15};
constexpr double kDeg = std::numbers::pi / 180.0;

NoiseOptions NoNoise() {
  NoiseOptions noise;
  noise.enabled = false;
  return noise;
}

// One box on the floor, turned by box_R_world, its lowest point on the floor.
Scene OneBoxScene(const BoxDims& dims, const Eigen::Matrix3d& world_R_box, double tilt_deg,
                  double camera_yaw_deg) {
  Scene scene;
  scene.world_T_camera = LookAtCamera(Eigen::Vector3d::Zero(), 1.2, tilt_deg, camera_yaw_deg, 0.0);
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = world_R_box;
  pose.translation().z() = 0.5 * world_R_box.row(2).cwiseAbs().dot(dims.vec());
  scene.boxes.push_back({dims, pose, true});
  return scene;
}

Eigen::Matrix3d Yaw(double deg) {
  return Eigen::AngleAxisd(deg * kDeg, Eigen::Vector3d::UnitZ()).matrix();
}

// The pose moved by `world_shift` (world frame, z up).
Eigen::Isometry3d Shifted(const Scene& scene, const Eigen::Isometry3d& camera_T_box,
                          const Eigen::Vector3d& world_shift) {
  Eigen::Isometry3d out = camera_T_box;
  out.translation() += scene.world_T_camera.linear().transpose() * world_shift;
  return out;
}

struct Rendered {
  Scene scene;
  RenderedScene out;
  DepthImage depth;
};

Rendered RenderScene(const Scene& scene, const NoiseOptions& noise) {
  Rendered r{scene, Render(scene, noise), {}};
  r.depth = MakeDepthImage(r.out.cloud, r.out.camera);
  return r;
}

void Print(const char* what, const BoxEvidence& ev) {
  std::cout << what << ": expected " << ev.total.expected << " support " << ev.support()
            << " see-through " << ev.see_through_fraction() << " occluded "
            << static_cast<double>(ev.total.occluded) / std::max(1, ev.total.expected) << " grasp "
            << BoxFaceName(ev.grasp_face) << "\n";
}

TEST(MeasureBoxTest, TruePoseIsConfirmedOnNoiseFreeRenders) {
  std::vector<Scene> scenes = {OneBoxScene(kCartonS, Yaw(0), 0.0, 0.0),
                               OneBoxScene(kCartonS, Yaw(30), 25.0, 60.0),
                               MakeIsolatedScene(kCartonS, 3, 4)};
  for (const Scene& scene : scenes) {
    const Rendered r = RenderScene(scene, NoNoise());
    for (const GroundTruthBox& gt : r.out.boxes) {
      const BoxEvidence ev = MeasureBox(r.depth, gt.camera_T_box, gt.dims, EvidenceOptions{});
      Print("true pose", ev);
      EXPECT_TRUE(ev.in_front_of_camera);
      EXPECT_GT(ev.total.expected, 500);
      EXPECT_GT(ev.support(), 0.95);
      EXPECT_LT(ev.see_through_fraction(), 0.01);
      EXPECT_GT(ev.visible_fraction(), 0.95);
      EXPECT_EQ(ev.grasp_face, gt.grasp_face);
      // Each face's counts add up.
      for (const FaceEvidence& f : ev.faces) {
        EXPECT_EQ(f.agree + f.occluded + f.see_through + f.missing, f.expected);
      }
    }
  }
}

TEST(MeasureBoxTest, TruePoseIsConfirmedOnNoisyRenders) {
  for (uint32_t seed : {1u, 2u}) {
    const Rendered r = RenderScene(MakeIsolatedScene(kCartonS, 3, seed), NoiseOptions{});
    for (const GroundTruthBox& gt : r.out.boxes) {
      const BoxEvidence ev = MeasureBox(r.depth, gt.camera_T_box, gt.dims, EvidenceOptions{});
      Print("true pose, noisy", ev);
      EXPECT_GT(ev.support(), 0.85);
      EXPECT_LT(ev.see_through_fraction(), 0.03);
    }
  }
}

TEST(MeasureBoxTest, PoseShiftedOntoTheFloorIsContradicted) {
  const Scene scene = OneBoxScene(kCartonS, Yaw(20), 15.0, 30.0);
  const Rendered r = RenderScene(scene, NoNoise());
  const GroundTruthBox& gt = r.out.boxes.at(0);
  for (const Eigen::Vector3d& shift :
       {Eigen::Vector3d(0.1, 0, 0), Eigen::Vector3d(0, -0.1, 0), Eigen::Vector3d(0.07, 0.07, 0)}) {
    const BoxEvidence ev =
        MeasureBox(r.depth, Shifted(scene, gt.camera_T_box, shift), kCartonS, EvidenceOptions{});
    Print("shifted 10 cm", ev);
    // Where it hangs over the floor the camera sees through it.
    EXPECT_GT(ev.see_through_fraction(), 0.2);
    EXPECT_LT(ev.support(), 0.7);
    // The detector's acceptance (max_see_through = 0.06) would reject it.
    EXPECT_GT(ev.see_through_fraction(), 0.06);
  }
}

TEST(MeasureBoxTest, BoxFloatingAboveTheTrueOneIsSeenThrough) {
  const Scene scene = OneBoxScene(kCartonS, Yaw(-15), 10.0, 0.0);
  const Rendered r = RenderScene(scene, NoNoise());
  const GroundTruthBox& gt = r.out.boxes.at(0);
  const BoxEvidence ev = MeasureBox(r.depth, Shifted(scene, gt.camera_T_box, {0, 0, 0.10}),
                                    kCartonS, EvidenceOptions{});
  Print("10 cm above", ev);
  // The measured top lies 10 cm behind the hypothesised one.
  EXPECT_GT(ev.see_through_fraction(), 0.9);
  EXPECT_LT(ev.support(), 0.1);
  EXPECT_EQ(ev.total.occluded, 0);
  EXPECT_GT(ev.grasp().see_through, 0.95 * ev.grasp().expected);
}

TEST(MeasureBoxTest, BoxSunkBelowTheTrueOneIsOccluded) {
  const Scene scene = OneBoxScene(kCartonS, Yaw(-15), 10.0, 0.0);
  const Rendered r = RenderScene(scene, NoNoise());
  const GroundTruthBox& gt = r.out.boxes.at(0);
  const BoxEvidence ev = MeasureBox(r.depth, Shifted(scene, gt.camera_T_box, {0, 0, -0.10}),
                                    kCartonS, EvidenceOptions{});
  Print("10 cm below", ev);
  // Its top is 10 cm under the measured one: hidden by the real box.
  EXPECT_GT(ev.grasp().occluded, 0.95 * ev.grasp().expected);
  EXPECT_LT(ev.visible_fraction(), 0.2);
  EXPECT_LT(ev.see_through_fraction(), 0.01);
}

TEST(MeasureBoxTest, GraspFaceIsTheFaceTowardTheCamera) {
  struct Case {
    Eigen::Matrix3d world_R_box;
    BoxFace up;  // the face that looks up, at a camera above
  };
  const Eigen::Matrix3d on_side = Eigen::AngleAxisd(90 * kDeg, Eigen::Vector3d::UnitX()).matrix();
  const Eigen::Matrix3d on_end = Eigen::AngleAxisd(-90 * kDeg, Eigen::Vector3d::UnitY()).matrix();
  const Eigen::Matrix3d upside_down =
      Eigen::AngleAxisd(180 * kDeg, Eigen::Vector3d::UnitX()).matrix();
  const std::vector<Case> cases = {{Yaw(10), BoxFace::kPlusZ},
                                   {Yaw(-40) * on_side, BoxFace::kPlusY},
                                   {Yaw(70) * on_end, BoxFace::kPlusX},
                                   {Yaw(5) * upside_down, BoxFace::kMinusZ}};
  for (const Case& c : cases) {
    const Scene scene = OneBoxScene(kCartonS, c.world_R_box, 10.0, 20.0);
    const Rendered r = RenderScene(scene, NoNoise());
    const GroundTruthBox& gt = r.out.boxes.at(0);
    const BoxEvidence ev = MeasureBox(r.depth, gt.camera_T_box, kCartonS, EvidenceOptions{});
    EXPECT_EQ(gt.grasp_face, c.up);
    EXPECT_EQ(ev.grasp_face, c.up) << BoxFaceName(ev.grasp_face);
    // The face's outward normal points to the camera.
    const Eigen::Vector3d n = gt.camera_T_box.linear() * BoxFaceNormal(ev.grasp_face);
    const Eigen::Vector3d centre =
        gt.camera_T_box *
        (BoxFaceNormal(ev.grasp_face) * 0.5 * kCartonS[static_cast<int>(ev.grasp_face) / 2]);
    EXPECT_GT(n.dot(-centre.normalized()), 0.9);
    EXPECT_GT(ev.grasp().agree, 0.95 * ev.grasp().expected);
  }
}

TEST(MeasureBoxTest, BoxBehindOrBesideTheCamera) {
  const Rendered r = RenderScene(OneBoxScene(kCartonS, Yaw(0), 0.0, 0.0), NoNoise());
  Eigen::Isometry3d behind = r.out.boxes.at(0).camera_T_box;
  behind.translation() = Eigen::Vector3d(0.0, 0.0, -1.0);
  EXPECT_FALSE(MeasureBox(r.depth, behind, kCartonS, EvidenceOptions{}).in_front_of_camera);
  Eigen::Isometry3d outside = r.out.boxes.at(0).camera_T_box;
  outside.translation() = Eigen::Vector3d(5.0, 0.0, 1.0);  // far right of the image
  const BoxEvidence ev = MeasureBox(r.depth, outside, kCartonS, EvidenceOptions{});
  EXPECT_TRUE(ev.in_front_of_camera);
  EXPECT_EQ(ev.total.expected, 0);
  EXPECT_EQ(ev.support(), 0.0);
}

TEST(MeasureBoxTest, SampleCountIsBounded) {
  const Rendered r = RenderScene(OneBoxScene(kCartonS, Yaw(0), 0.0, 0.0), NoNoise());
  EvidenceOptions few;
  few.max_samples = 200;
  const BoxEvidence ev = MeasureBox(r.depth, r.out.boxes[0].camera_T_box, kCartonS, few);
  EXPECT_GT(ev.total.expected, 50);
  EXPECT_LE(ev.total.expected, 400);
  EXPECT_GT(ev.support(), 0.95);
}

// Stereo cameras lose or smear the pixels along a box's occluding outline
// (edge fattening, flying pixels between the box and the floor behind it):
// those are counted as border, not as seen through, while a box moved off
// the real one is still contradicted.
TEST(MeasureBoxTest, PixelsLostAlongTheOutlineAreBorderNotSeeThrough) {
  const Rendered r = RenderScene(OneBoxScene(kCartonS, Yaw(20), 30.0, 40.0), NoNoise());
  // Every pixel within 2 px of a jump to something 5 cm farther gets the
  // depth of what lies behind (a ragged, fattened outline).
  DepthImage smeared = r.depth;
  const int w = r.depth.camera.width, h = r.depth.camera.height;
  for (int v = 2; v < h - 2; ++v) {
    for (int u = 2; u < w - 2; ++u) {
      const float z = r.depth.at(u, v);
      float farthest = z;
      for (int dv = -2; dv <= 2; ++dv) {
        for (int du = -2; du <= 2; ++du) farthest = std::max(farthest, r.depth.at(u + du, v + dv));
      }
      if (farthest > z + 0.05f) smeared.z[static_cast<size_t>(v) * w + u] = farthest;
    }
  }
  const GroundTruthBox& gt = r.out.boxes[0];
  EvidenceOptions none;
  none.outline_margin_m = 0.0;
  const BoxEvidence counted = MeasureBox(smeared, gt.camera_T_box, gt.dims, none);
  const BoxEvidence discounted = MeasureBox(smeared, gt.camera_T_box, gt.dims, EvidenceOptions{});
  Print("outline counted", counted);
  Print("outline discounted", discounted);
  EXPECT_EQ(counted.total.border, 0);
  EXPECT_GT(counted.see_through_fraction(), 0.02);
  EXPECT_GT(discounted.total.border, 0);
  EXPECT_LT(discounted.see_through_fraction(), 0.005);
  EXPECT_GT(discounted.support(), 0.95);
  // 6 cm off along the floor: far more than the margin, still seen through.
  const BoxEvidence moved =
      MeasureBox(smeared, Shifted(r.scene, gt.camera_T_box, Eigen::Vector3d(0.06, 0.0, 0.0)),
                 gt.dims, EvidenceOptions{});
  Print("moved 6 cm", moved);
  EXPECT_GT(moved.see_through_fraction() + (1.0 - moved.support()), 0.1);
}

// A time-of-flight camera's multipath (light bouncing off the floor into a
// box's side near the crease where they meet) reads the sides centimetres
// too far: on the box's faces but the one it shows most, that is no
// evidence either way. Seen from above at an angle, so the sides show.
TEST(MeasureBoxTest, TimeOfFlightMultipathOnTheSidesIsNotSeeThrough) {
  SensorOptions tof;
  tof.kind = SensorKind::kTimeOfFlight;
  EvidenceOptions strict;
  strict.side_face_allowance_m = 0.0;
  double worst_strict = 0.0;
  // The camera looks at a point 0.45-0.55 m beside the box, so the box
  // lies towards the image's edge and its sides face the camera.
  for (const auto& [look_x, look_y, box_yaw] :
       {std::tuple{0.45, 0.2, 20.0}, std::tuple{-0.35, 0.3, 60.0}, std::tuple{0.3, -0.45, -35.0},
        std::tuple{-0.45, -0.25, 10.0}}) {
    Scene scene = OneBoxScene(BoxDims{0.25, 0.25, 0.20}, Yaw(box_yaw), 0.0, 0.0);
    scene.world_T_camera = LookAtCamera(Eigen::Vector3d(look_x, look_y, 0.0), 1.1, 10.0, 30.0, 0.0);
    RenderedScene out = Render(scene, tof);
    const DepthImage depth = MakeDepthImage(out.cloud, out.camera);
    const GroundTruthBox& gt = out.boxes.at(0);
    const BoxEvidence without = MeasureBox(depth, gt.camera_T_box, gt.dims, strict);
    const BoxEvidence with = MeasureBox(depth, gt.camera_T_box, gt.dims, EvidenceOptions{});
    Print("tof, no allowance", without);
    Print("tof, side allowance", with);
    worst_strict = std::max(worst_strict, without.see_through_fraction());
    // The main face gets no allowance: it reads the same.
    EXPECT_EQ(with.grasp().see_through, without.grasp().see_through);
    EXPECT_LT(with.see_through_fraction(), 0.03);
    EXPECT_GT(with.support(), 0.9);
  }
  // Without it, some view's sides read as seen through beyond the
  // acceptance's 5 %.
  EXPECT_GT(worst_strict, 0.05);
}

// The allowance does not let a box stand where there is free space: moved
// off the real box along the floor, or floating above it, it is seen
// through on its main face.
TEST(MeasureBoxTest, SideAllowanceKeepsMisplacedBoxesSeenThrough) {
  const Scene scene = OneBoxScene(kCartonS, Yaw(25), 30.0, 40.0);
  const Rendered r = RenderScene(scene, NoNoise());
  const GroundTruthBox& gt = r.out.boxes.at(0);
  for (const Eigen::Vector3d& shift :
       {Eigen::Vector3d(0.08, 0, 0), Eigen::Vector3d(0, 0.08, 0), Eigen::Vector3d(0, 0, 0.05)}) {
    const BoxEvidence ev =
        MeasureBox(r.depth, Shifted(scene, gt.camera_T_box, shift), kCartonS, EvidenceOptions{});
    Print("misplaced, side allowance", ev);
    EXPECT_GT(ev.see_through_fraction(), 0.1);
  }
}

TEST(EvidenceOptionsTest, InvalidOptionsAreRefused) {
  EXPECT_TRUE(EvidenceOptions{}.Validate().ok());
  EvidenceOptions o;
  o.depth_tolerance_base_m = 0.0;
  EXPECT_EQ(o.Validate().code(), absl::StatusCode::kInvalidArgument);
  o = EvidenceOptions{};
  o.max_samples = 5;
  EXPECT_EQ(o.Validate().code(), absl::StatusCode::kInvalidArgument);
  o = EvidenceOptions{};
  o.outline_margin_m = -0.01;
  EXPECT_EQ(o.Validate().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(o.Validate().message().find("outline_margin_m"), std::string::npos);
  o = EvidenceOptions{};
  o.side_face_allowance_m = 0.5;
  EXPECT_NE(o.Validate().message().find("side_face_allowance_m"), std::string::npos);
}

}  // namespace
}  // namespace cornerpose::testing
