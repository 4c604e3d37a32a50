// A grasp face the image border cuts on one side (internal/border_faces.h):
// pinned when what is in view says which face of the box it is and where
// it ends; otherwise declined, as every face cut by the border was before.
#include "common/perception/internal/border_faces.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>

#include "common/perception/internal/hypothesis_judge.h"
#include "common/perception/pose_error.h"
#include "tests/support/scene_generator.h"

namespace cornerpose::testing {
namespace {

constexpr BoxDims kCartonS{0.30, 0.20, 0.15};
constexpr BoxDims kSquareTop{0.30, 0.30, 0.20};
constexpr double kDistance = 1.1;  // camera to the box's top, metres

// One box lying on the floor, seen straight down (its x axis along the
// image's u), with the principal point moved so that only `share` of its
// top's length along x lies in view: its -x side is out past the image's
// left border. No noise.
struct CutBox {
  RenderedScene out;
  DepthImage depth;
};
// Turned by `yaw_deg` about the vertical, the border cuts the top aslant:
// `share` of its length lies in view along its middle line.
CutBox RenderCut(const BoxDims& dims, double share, double yaw_deg = 0.0) {
  Scene scene;
  const double yaw = yaw_deg * std::numbers::pi / 180.0;
  // The top's centre projects at u = cx; along its middle line the border
  // (u = 0) lies share * l from its +x side.
  scene.camera.cx = scene.camera.fx / kDistance * std::cos(yaw) * dims.l * (share - 0.5);
  scene.world_T_camera = LookAtCamera(Eigen::Vector3d(0.0, 0.0, dims.h), kDistance, 0.0, 0.0, 0.0);
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  pose.translation().z() = dims.h / 2.0;
  scene.boxes.push_back({dims, pose, true});
  NoiseOptions noise;
  noise.enabled = false;
  CutBox b{Render(scene, noise), {}};
  b.depth = MakeDepthImage(b.out.cloud, b.out.camera);
  return b;
}

// The judge's verdict on the true pose alone: the accepted pose, or none.
std::optional<Eigen::Isometry3d> Judged(const CutBox& b, const BoxDims& dims, bool may_run_out) {
  DetectorOptions o;
  o.box = dims;
  o.acceptance.face_may_run_out_of_view = may_run_out;
  const internal::HypothesisJudge judge(b.depth, o);
  const std::optional<internal::Candidate> c = judge.JudgeAlone(b.out.boxes.at(0).camera_T_box);
  if (!c) return std::nullopt;
  return c->box.camera_T_box;
}

// The refinement's reading of the true pose, and the side it pins.
int PinnedSide(const CutBox& b, const BoxDims& dims, bool border_band_ends_view = true) {
  DetectorOptions o;
  o.box = dims;
  o.acceptance.border_band_ends_view = border_band_ends_view;
  Eigen::Isometry3d pose = b.out.boxes.at(0).camera_T_box;
  const RefinementResult ref =
      RefineOnGraspFace(b.depth, dims, BoxFace::kPlusZ, o.refinement, &pose);
  return internal::SideOutOfViewPinned(b.depth, pose, BoxFace::kPlusZ, dims, ref, o.acceptance,
                                       o.refinement.plane_tolerance_m);
}

// Three quarters of a carton's top in view along its 0.30 m side: no other
// side of the box (0.15 m, its height) is that long, so it is this face,
// ended where its measured right side and its size say. Found, where it
// is; declined with the rule off, as before.
TEST(BorderFacesTest, AFaceThreeQuartersInViewIsPinnedByItsSize) {
  const CutBox b = RenderCut(kCartonS, 0.75);
  EXPECT_EQ(PinnedSide(b, kCartonS), 1);  // -a: the box's -x side
  const std::optional<Eigen::Isometry3d> found = Judged(b, kCartonS, true);
  ASSERT_TRUE(found.has_value());
  const PoseError e = ComparePoses(*found, b.out.boxes.at(0).camera_T_box, kCartonS);
  EXPECT_LT(e.translation_m, 0.01);
  EXPECT_LT(e.rotation_deg, 2.0);
  EXPECT_FALSE(Judged(b, kCartonS, false).has_value());
}

// Less than min_in_view_share in view: where a gripper would aim, the
// face's centre, is too near the border to trust. Declined.
TEST(BorderFacesTest, AFaceMostlyOutOfViewIsDeclined) {
  const CutBox b = RenderCut(kCartonS, 0.5);
  EXPECT_EQ(PinnedSide(b, kCartonS), -1);
  EXPECT_FALSE(Judged(b, kCartonS, true).has_value());
}

// A square top (0.30 x 0.30) with 0.21 m of one side in view could as
// well be the 0.30 x 0.20 side of the box standing on end: not pinned
// until more than 0.20 m + the extent tolerance is seen.
TEST(BorderFacesTest, AFaceAShorterSideOfTheBoxCouldExplainIsNotPinned) {
  const CutBox short_of_it = RenderCut(kSquareTop, 0.7);
  EXPECT_EQ(PinnedSide(short_of_it, kSquareTop), -1);
  EXPECT_FALSE(Judged(short_of_it, kSquareTop, true).has_value());
  const CutBox past_it = RenderCut(kSquareTop, 0.85);
  EXPECT_EQ(PinnedSide(past_it, kSquareTop), 1);
  EXPECT_TRUE(Judged(past_it, kSquareTop, true).has_value());
}

// A square top turned 15 degrees, 0.24 m of its 0.30 m side in view along
// its middle line: the border cuts it aslant, and only the line along its
// far side sees it past the 0.20 m side of the box standing on end (+ the
// extent tolerance). That line says which face it is; the others, shorter,
// need only be on its plane. Not pinned when no line sees that far.
TEST(BorderFacesTest, AFaceTheBorderCutsAslantIsPinnedByTheLineThatSeesPastTheShorterSide) {
  const CutBox aslant = RenderCut(kSquareTop, 0.8, 15.0);
  EXPECT_EQ(PinnedSide(aslant, kSquareTop), 1);
  const std::optional<Eigen::Isometry3d> found = Judged(aslant, kSquareTop, true);
  ASSERT_TRUE(found.has_value());
  const PoseError e = ComparePoses(*found, aslant.out.boxes.at(0).camera_T_box, kSquareTop);
  EXPECT_LT(e.translation_m, 0.01);
  EXPECT_LT(e.rotation_deg, 2.0);
  EXPECT_EQ(PinnedSide(RenderCut(kSquareTop, 0.68, 15.0), kSquareTop), -1);
}

// An active stereo camera returns nothing in a band along one side of its
// image: here the 20 columns at the left border. The carton's top, 0.225 m
// of 0.30 in view, shows on its plane for 0.18 m, past its 0.15 m height
// (+ the tolerance): the view ends where the band begins, and the face is
// pinned. Counted as pixels off the face, the band unpins it.
TEST(BorderFacesTest, ABandWithNoReturnAtTheBorderEndsTheView) {
  CutBox b = RenderCut(kCartonS, 0.75);
  for (int v = 0; v < b.depth.camera.height; ++v) {
    for (int u = 0; u < 20; ++u) {
      b.depth.z[static_cast<size_t>(v) * b.depth.camera.width + u] =
          std::numeric_limits<float>::quiet_NaN();
    }
  }
  EXPECT_EQ(PinnedSide(b, kCartonS, true), 1);
  EXPECT_EQ(PinnedSide(b, kCartonS, false), -1);
}

// The side SideOutOfViewPinned pins for the true pose of `b`, read with
// `grasp` as its grasp face and the refinement's reading `sides`.
int PinnedWithSides(const CutBox& b, BoxFace grasp, const std::array<SideKind, 4>& sides) {
  DetectorOptions o;
  o.box = kCartonS;
  RefinementResult ref;
  ref.ok = true;
  ref.sides = sides;
  return internal::SideOutOfViewPinned(b.depth, b.out.boxes.at(0).camera_T_box, grasp, kCartonS,
                                       ref, o.acceptance, o.refinement.plane_tolerance_m);
}

// The carton's 0.20 x 0.15 end face as the grasp face (+x), its 0.20 m
// side running out of view: the box's 0.30 m side could go on there, out
// of view (a carton lying on its side, not standing on end). Never pinned,
// however much of it is in view; its top (+z) with the same sides is.
TEST(BorderFacesTest, AFaceALongerSideOfTheBoxCouldContinueIsNotPinned) {
  const CutBox b = RenderCut(kCartonS, 0.75);
  const std::array<SideKind, 4> sides{SideKind::kFree, SideKind::kUnknown, SideKind::kFree,
                                      SideKind::kFree};
  EXPECT_EQ(PinnedWithSides(b, BoxFace::kPlusX, sides), -1);
  EXPECT_EQ(PinnedWithSides(b, BoxFace::kPlusZ, sides), 1);
}

// Two sides not measured (a face at a corner of the view, or a side that
// is hidden as well as one out of view): nothing pins it.
TEST(BorderFacesTest, AFaceWithTwoSidesUnmeasuredIsNotPinned) {
  const CutBox b = RenderCut(kCartonS, 0.75);
  EXPECT_EQ(
      PinnedWithSides(b, BoxFace::kPlusZ,
                      {SideKind::kFree, SideKind::kUnknown, SideKind::kFree, SideKind::kOccluded}),
      -1);
  EXPECT_EQ(
      PinnedWithSides(b, BoxFace::kPlusZ,
                      {SideKind::kFree, SideKind::kUnknown, SideKind::kFree, SideKind::kFree}),
      1);
}

}  // namespace
}  // namespace cornerpose::testing
