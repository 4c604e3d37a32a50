// The judge's queue: a pose like one already judged is not judged again,
// but one refined and declined gets one more start from a later proposal
// (DetectorOptions::retry_declined).
#include "common/perception/internal/hypothesis_judge.h"

#include <gtest/gtest.h>

#include "tests/support/scene_generator.h"

namespace cornerpose::testing {
namespace {

constexpr BoxDims kCartonS{0.30, 0.20, 0.15};

struct OneBox {
  RenderedScene out;
  DepthImage depth;
};

// `cx`: the camera's principal point (a small one puts the box, which the
// camera looks at, at the image's left edge).
OneBox RenderOneBox(double cx = CameraIntrinsics{}.cx) {
  Scene scene;
  scene.camera.cx = cx;
  scene.world_T_camera = LookAtCamera(Eigen::Vector3d::Zero(), 1.2, 10.0, 20.0, 0.0);
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation().z() = kCartonS.h / 2.0;
  scene.boxes.push_back({kCartonS, pose, true});
  NoiseOptions noise;
  noise.enabled = false;
  OneBox b{Render(scene, noise), {}};
  b.depth = MakeDepthImage(b.out.cloud, b.out.camera);
  return b;
}

Eigen::Isometry3d Moved(const Eigen::Isometry3d& pose, double dx) {
  Eigen::Isometry3d out = pose;
  out.translation().x() += dx;
  return out;
}

TEST(HypothesisJudgeTest, ADeclinedPoseIsJudgedOnceMoreFromAnotherStart) {
  const OneBox b = RenderOneBox();
  const Eigen::Isometry3d gt = b.out.boxes.at(0).camera_T_box;
  for (const bool retry : {true, false}) {
    DetectorOptions o;
    o.box = kCartonS;
    o.retry_declined = retry;
    // Every refined hypothesis is declined: the face is never big enough.
    o.acceptance.min_grasp_pixels = 1000000;
    internal::HypothesisJudge judge(b.depth, o);
    judge.Propose(gt, 0, {});
    EXPECT_TRUE(judge.Evaluate(1).empty());
    EXPECT_EQ(judge.stats().refined, 1);
    ASSERT_EQ(judge.declined().size(), 1u);
    EXPECT_EQ(judge.declined()[0].reason, "grasp face too small in the image");
    // A proposal within a centimetre of it: judged again only with retry.
    judge.Propose(Moved(gt, 0.004), 0, {});
    judge.Evaluate(1);
    EXPECT_EQ(judge.stats().refined, retry ? 2 : 1);
    // ... and only once.
    judge.Propose(Moved(gt, -0.004), 0, {});
    judge.Evaluate(1);
    EXPECT_EQ(judge.stats().refined, retry ? 2 : 1);
  }
}

TEST(HypothesisJudgeTest, AnAcceptedPoseIsNotJudgedAgain) {
  const OneBox b = RenderOneBox();
  const Eigen::Isometry3d gt = b.out.boxes.at(0).camera_T_box;
  DetectorOptions o;
  o.box = kCartonS;
  internal::HypothesisJudge judge(b.depth, o);
  judge.Propose(gt, 0, {});
  EXPECT_EQ(judge.Evaluate(1).size(), 1u);
  judge.Propose(Moved(gt, 0.004), 0, {});
  EXPECT_TRUE(judge.Evaluate(1).empty());
  EXPECT_EQ(judge.stats().proposed, 1);
  EXPECT_EQ(judge.stats().refined, 1);
}

// A pose whose grasp face runs out of the image but whose face centre and
// some of each side are in view goes on to refinement when a face measured
// on every side may leave the view (the final check then decides); with
// that rule off, the first look drops it, as before; and so it does, rule
// or not, when a whole side is out of view (that side cannot be measured).
// With the principal point at u = 64 the face's far-left corner lies at
// u = -24 and its left side's upper quarter point at u = 3; at u = 30 the
// whole left side is out.
TEST(HypothesisJudgeTest, AFaceLeavingTheViewIsRefinedWhenItMayBeMeasuredThere) {
  const OneBox out_a_side = RenderOneBox(/*cx=*/30.0);
  for (const bool may_leave : {true, false}) {
    DetectorOptions o;
    o.box = kCartonS;
    o.acceptance.measured_face_may_leave_view = may_leave;
    internal::HypothesisJudge judge(out_a_side.depth, o);
    judge.Propose(out_a_side.out.boxes.at(0).camera_T_box, 0, {});
    judge.Evaluate(1);
    EXPECT_EQ(judge.stats().refined, 0) << may_leave;
  }
  const OneBox b = RenderOneBox(/*cx=*/64.0);
  const Eigen::Isometry3d gt = b.out.boxes.at(0).camera_T_box;
  for (const bool may_leave : {true, false}) {
    DetectorOptions o;
    o.box = kCartonS;
    o.acceptance.measured_face_may_leave_view = may_leave;
    internal::HypothesisJudge judge(b.depth, o);
    judge.Propose(gt, 0, {});
    judge.Evaluate(1);
    EXPECT_EQ(judge.stats().refined, may_leave ? 1 : 0) << may_leave;
  }
}

}  // namespace
}  // namespace cornerpose::testing
