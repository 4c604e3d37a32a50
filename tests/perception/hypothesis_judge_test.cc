// The judge's queue: a pose like one already judged is not judged again,
// but one refined and declined gets one more start from a later proposal
// (DetectorOptions::retry_declined); a neighbour declined for a side on
// flat is a stepping stone (DetectorOptions::neighbour_steps_past_declined).
#include "common/perception/internal/hypothesis_judge.h"

#include <gtest/gtest.h>

#include "common/perception/box_pose.h"
#include "common/perception/camera_model.h"
#include "common/perception/internal/box_overlap.h"
#include "common/perception/pose_error.h"
#include "tests/support/scene_generator.h"

namespace cornerpose::testing {
namespace {

constexpr BoxDims kCartonS{0.30, 0.20, 0.15};

struct RenderedDepth {
  RenderedScene out;
  DepthImage depth;
};

// The scene rendered without noise, and its depth image.
RenderedDepth RenderNoiseFree(const Scene& scene) {
  NoiseOptions noise;
  noise.enabled = false;
  RenderedDepth b{Render(scene, noise), {}};
  b.depth = MakeDepthImage(b.out.cloud, b.out.camera);
  return b;
}

// `cx`: the camera's principal point (a small one puts the box, which the
// camera looks at, at the image's left edge).
RenderedDepth RenderOneBox(double cx = CameraIntrinsics{}.cx) {
  Scene scene;
  scene.camera.cx = cx;
  scene.world_T_camera = LookAtCamera(Eigen::Vector3d::Zero(), 1.2, 10.0, 20.0, 0.0);
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation().z() = kCartonS.h / 2.0;
  scene.boxes.push_back({kCartonS, pose, true});
  return RenderNoiseFree(scene);
}

Eigen::Isometry3d Moved(const Eigen::Isometry3d& pose, double dx) {
  Eigen::Isometry3d out = pose;
  out.translation().x() += dx;
  return out;
}

TEST(HypothesisJudgeTest, ADeclinedPoseIsJudgedOnceMoreFromAnotherStart) {
  const RenderedDepth b = RenderOneBox();
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

// A corner proposes both readings of its box; the one turned the wrong way
// runs on flat past the true box's shorter side and is declined. Declined
// so, it proposes its face turned a quarter at its measured corners
// (DetectorOptions::turned_proposals): the next round judges the true box.
TEST(HypothesisJudgeTest, AReadingDeclinedOnFlatProposesItsTurnedReadings) {
  // Two cartons side by side along their 0.20 m sides, 4 mm apart.
  Scene scene;
  scene.world_T_camera = LookAtCamera(Eigen::Vector3d::Zero(), 1.2, 10.0, 20.0, 0.0);
  for (const double y : {0.0, kCartonS.b + 0.004}) {
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.translation() = Eigen::Vector3d(0.0, y, kCartonS.h / 2.0);
    scene.boxes.push_back({kCartonS, pose, true});
  }
  const RenderedDepth b = RenderNoiseFree(scene);
  const Eigen::Isometry3d gt = b.out.boxes.at(0).camera_T_box;
  const BoxFace top = b.out.boxes.at(0).grasp_face;
  ASSERT_EQ(top, BoxFace::kPlusZ);
  // The wrong reading: the first carton's face turned a quarter at its
  // outer corner (+x, -y), reaching into the second carton.
  const Eigen::Isometry3d wrong = internal::TurnedAtCorner(gt, top, kCartonS, 1.0, -1.0);
  for (const bool turned : {true, false}) {
    DetectorOptions o;
    o.box = kCartonS;
    o.turned_proposals = turned;
    internal::HypothesisJudge judge(b.depth, o);
    judge.Propose(wrong, 0, {});
    EXPECT_TRUE(judge.Evaluate(1).empty());
    ASSERT_EQ(judge.declined().size(), 1u);
    EXPECT_EQ(judge.declined()[0].reason.rfind("a side runs on flat", 0), 0u)
        << judge.declined()[0].reason;
    EXPECT_EQ(judge.Queued(), turned);
    const std::vector<internal::Candidate> next = judge.Evaluate(1);
    if (!turned) {
      EXPECT_TRUE(next.empty());
      continue;
    }
    ASSERT_EQ(next.size(), 1u);
    const PoseError e = ComparePoses(next[0].box.camera_T_box, gt, kCartonS);
    EXPECT_LT(e.translation_m, 0.01);
    EXPECT_LT(e.rotation_deg, 2.0);
  }
}

TEST(HypothesisJudgeTest, AnAcceptedPoseIsNotJudgedAgain) {
  const RenderedDepth b = RenderOneBox();
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

// A plane no box may reach through (HypothesisJudge::SetFloor, the floor
// DetectorOptions::floor_check finds): a box lying on it is accepted; with
// the plane raised 5 cm toward the camera, the same box reaches 5 cm
// through it and is declined when judged.
TEST(HypothesisJudgeTest, AHypothesisThroughTheFloorIsDeclinedWhenJudged) {
  const RenderedDepth b = RenderOneBox();
  const Eigen::Isometry3d gt = b.out.boxes.at(0).camera_T_box;
  DetectorOptions o;
  o.box = kCartonS;
  const Eigen::Vector3d n = b.out.floor_plane_camera.head<3>();  // towards the camera
  const Eigen::Vector3d on_floor = -b.out.floor_plane_camera.w() * n;
  for (const double raised : {0.0, 0.05}) {
    internal::HypothesisJudge judge(b.depth, o);
    judge.SetFloor(n, on_floor + raised * n, 0.03);
    judge.Propose(gt, 0, {});
    const std::vector<internal::Candidate> accepted = judge.Evaluate(1);
    if (raised == 0.0) {
      EXPECT_EQ(accepted.size(), 1u);
      continue;
    }
    EXPECT_TRUE(accepted.empty());
    ASSERT_EQ(judge.declined().size(), 1u);
    EXPECT_NE(judge.declined()[0].reason.find("into the floor"), std::string::npos)
        << judge.declined()[0].reason;
    // Judged alone (as tools/judge_poses does), with the reason.
    std::string why;
    EXPECT_FALSE(judge.JudgeAlone(gt, {}, &why).has_value());
    EXPECT_NE(why.find("into the floor"), std::string::npos) << why;
  }
}

// With the floor raised further (20 cm toward the camera, the carton lying
// on the true floor reaching that far through it), no refinement within
// its 5 cm and 12 degrees could bring it out: it is not refined at all, and
// not listed as declined. Raised 10 cm (within reach: 3 cm of tolerance, 5
// cm of shift and ~4 cm a corner moves as the box turns 12 degrees) it is
// refined and then declined, as above.
TEST(HypothesisJudgeTest, AHypothesisBeyondRefinementsReachThroughTheFloorIsNotRefined) {
  const RenderedDepth b = RenderOneBox();
  const Eigen::Isometry3d gt = b.out.boxes.at(0).camera_T_box;
  DetectorOptions o;
  o.box = kCartonS;
  const Eigen::Vector3d n = b.out.floor_plane_camera.head<3>();
  const Eigen::Vector3d on_floor = -b.out.floor_plane_camera.w() * n;
  for (const double raised : {0.10, 0.20}) {
    SCOPED_TRACE(::testing::Message() << "raised " << raised);
    internal::HypothesisJudge judge(b.depth, o);
    judge.SetFloor(n, on_floor + raised * n, 0.03);
    judge.Propose(gt, 0, {});
    EXPECT_TRUE(judge.Evaluate(1).empty());
    EXPECT_EQ(judge.stats().refined, raised < 0.15 ? 1 : 0);
    EXPECT_EQ(judge.declined().size(), raised < 0.15 ? 1u : 0u);
  }
}

// A carton whose grasp face has one corner a few pixels past the image's
// left edge, one long side under a taller box standing in front of it (read
// occluded) and the other three free: judged as in view
// (AcceptanceOptions::max_out_of_view_share), it is accepted; with the rule
// off, its face is cut by the border and not pinned on every side.
TEST(HypothesisJudgeTest, AFaceWithACornerJustPastTheBorderIsJudgedAsInView) {
  const BoxDims tall{0.30, 0.20, 0.35};
  Eigen::Isometry3d carton = Eigen::Isometry3d::Identity();
  carton.translation().z() = kCartonS.h / 2.0;
  Eigen::Isometry3d in_front = Eigen::Isometry3d::Identity();
  in_front.translation() = Eigen::Vector3d(0.0, -(kCartonS.b + tall.b) / 2.0 - 0.004, tall.h / 2.0);
  Scene scene;
  scene.world_T_camera = LookAtCamera(Eigen::Vector3d(0.0, 0.02, kCartonS.h), 1.3, -12.0, 8.0, 0.0);
  scene.boxes = {{kCartonS, carton, true}, {tall, in_front, true}};
  // The principal point that puts the face's leftmost corner 4 px past the
  // left edge.
  const RenderedDepth centred = RenderNoiseFree(scene);
  const Eigen::Isometry3d& gt = centred.out.boxes.at(0).camera_T_box;
  double u_min = 1e9;
  for (const double sx : {-0.5, 0.5}) {
    for (const double sy : {-0.5, 0.5}) {
      const Eigen::Vector3d p =
          gt * Eigen::Vector3d(sx * kCartonS.l, sy * kCartonS.b, kCartonS.h / 2);
      u_min = std::min(u_min, Project(scene.camera, p).x());
    }
  }
  scene.camera.cx -= u_min + 4.0;
  const RenderedDepth b = RenderNoiseFree(scene);
  const Eigen::Isometry3d& pose = b.out.boxes.at(0).camera_T_box;
  for (const double share : {0.1, 0.0}) {
    DetectorOptions o;
    o.box = kCartonS;
    o.acceptance.max_out_of_view_share = share;
    internal::HypothesisJudge judge(b.depth, o);
    std::string why;
    const std::optional<internal::Candidate> c = judge.JudgeAlone(pose, {}, &why);
    if (share > 0.0) {
      ASSERT_TRUE(c.has_value()) << why;
      EXPECT_EQ(c->refinement.free_sides, 3);
      EXPECT_LT(ComparePoses(c->box.camera_T_box, pose, kCartonS).translation_m, 0.005);
    } else {
      EXPECT_FALSE(c.has_value());
      EXPECT_EQ(why, "grasp face cut by the image border");
    }
  }
  AcceptanceOptions bad;
  bad.max_out_of_view_share = 1.0;  // the whole face out of view
  EXPECT_NE(std::string(bad.Validate().message()).find("max_out_of_view_share"), std::string::npos);
}

// A corner hypothesis tilted 15 degrees off a carton's top (about an axis
// in the face through its centre, as a segment's depth noise tilts it) is
// turned back onto the depth's plane; one tilted 1 degree is left as it is,
// and so is a face too small in the image to fit a plane to.
TEST(HypothesisJudgeTest, ATiltedCornerReadingTurnsOntoTheDepthsPlane) {
  const RenderedDepth b = RenderOneBox();
  const Eigen::Isometry3d gt = b.out.boxes.at(0).camera_T_box;
  const Eigen::Vector3d top = gt.linear().col(2);  // the +z face, towards the camera
  auto tilted = [&](double deg) {
    const Eigen::Vector3d centre = gt * Eigen::Vector3d(0.0, 0.0, kCartonS.h / 2.0);
    const Eigen::Matrix3d turn =
        Eigen::AngleAxisd(deg * M_PI / 180.0, gt.linear().col(0)).toRotationMatrix();
    Eigen::Isometry3d pose = gt;
    pose.linear() = turn * gt.linear();
    pose.translation() = centre + turn * (gt.translation() - centre);
    return pose;
  };
  Eigen::Isometry3d pose = tilted(15.0);
  ASSERT_TRUE(internal::TiltOntoDepth(b.depth, kCartonS, &pose));
  EXPECT_LT(std::acos(std::min(1.0, pose.linear().col(2).dot(top))) * 180.0 / M_PI, 1.0);
  EXPECT_LT((pose.translation() - gt.translation()).norm(), 0.01);
  pose = tilted(1.0);
  EXPECT_FALSE(internal::TiltOntoDepth(b.depth, kCartonS, &pose));
  // A 4 cm cube's face spans ~17 px at 1.2 m: left as it is.
  pose = tilted(15.0);
  EXPECT_FALSE(internal::TiltOntoDepth(b.depth, BoxDims{0.04, 0.04, 0.04}, &pose));
}

// A hypothesis that overlaps a kept box by more than refinement can move it
// (AcceptanceOptions::settled_overlap_margin_m, 5 cm on every side) is not
// judged while the box is kept, and is judged when proposed again once the
// box is gone; one that overlaps it less (7 cm along the 0.30 m side:
// refinement could move it off) is judged; with the margin 0, every one is.
TEST(HypothesisJudgeTest, AHypothesisDeepInsideAKeptBoxIsNotJudged) {
  const RenderedDepth b = RenderOneBox();
  const Eigen::Isometry3d gt = b.out.boxes.at(0).camera_T_box;
  DetectedBox kept;
  kept.camera_T_box = gt;
  for (const double margin : {0.05, 0.0}) {
    DetectorOptions o;
    o.box = kCartonS;
    o.acceptance.settled_overlap_margin_m = margin;
    internal::HypothesisJudge judge(b.depth, o);
    // 2 cm off the kept box: deep inside it.
    judge.Propose(Moved(gt, 0.02), 0, {});
    const std::vector<internal::Candidate> deep = judge.Evaluate(1, {kept});
    EXPECT_EQ(judge.stats().refined, margin > 0.0 ? 0 : 1) << margin;
    EXPECT_EQ(judge.stats().proposed, margin > 0.0 ? 0 : 1) << margin;
    EXPECT_EQ(deep.size(), margin > 0.0 ? 0u : 1u) << margin;
    // Its box gone, the same hypothesis is judged (and is the box).
    judge.Propose(Moved(gt, 0.02), 0, {});
    const std::vector<internal::Candidate> freed = judge.Evaluate(1, {});
    if (margin > 0.0) {
      ASSERT_EQ(freed.size(), 1u);
      EXPECT_LT(ComparePoses(freed[0].box.camera_T_box, gt, kCartonS).translation_m, 0.005);
    }
    EXPECT_EQ(judge.stats().refined, 1) << margin;
  }
  // Shifted by 0.23 m along the box's 0.30 m side (x): it overlaps the kept
  // box by 7 cm, less than twice the margin, so it is judged.
  DetectorOptions o;
  o.box = kCartonS;
  const Eigen::Isometry3d along = gt * Eigen::Translation3d(0.23, 0.0, 0.0);
  ASSERT_TRUE(internal::BoxesOverlap(gt, along, kCartonS, o.acceptance.overlap_margin_m));
  internal::HypothesisJudge judge(b.depth, o);
  judge.Propose(along, 0, {});
  judge.Evaluate(1, {kept});
  EXPECT_EQ(judge.stats().proposed, 1);
}

// Within one batch, a hypothesis inside a box accepted before it (in the
// order proposed) is not judged (AcceptanceOptions::settle_within_batch):
// the box comes out once, refined once, on one thread or two (the second
// thread may judge it before the first is accepted; that verdict is
// dropped). Rule off: both are judged and accepted.
TEST(HypothesisJudgeTest, AHypothesisInsideOneAcceptedEarlierInItsBatchIsNotJudged) {
  const RenderedDepth b = RenderOneBox();
  const Eigen::Isometry3d gt = b.out.boxes.at(0).camera_T_box;
  for (const bool within : {true, false}) {
    for (const int threads : {1, 2}) {
      DetectorOptions o;
      o.box = kCartonS;
      o.acceptance.settle_within_batch = within;
      internal::HypothesisJudge judge(b.depth, o);
      judge.Propose(gt, 0, {});
      judge.Propose(Moved(gt, 0.02), 0, {});
      const std::vector<internal::Candidate> found = judge.Evaluate(threads);
      ASSERT_EQ(found.size(), within ? 1u : 2u) << within << " " << threads;
      EXPECT_EQ(judge.stats().refined, within ? 1 : 2) << within << " " << threads;
      EXPECT_EQ(judge.stats().proposed, within ? 1 : 2) << within << " " << threads;
      EXPECT_LT(ComparePoses(found[0].box.camera_T_box, gt, kCartonS).translation_m, 0.005);
      // The one not judged may be proposed again (as if never proposed).
      judge.Propose(Moved(gt, 0.02), 0, {});
      EXPECT_EQ(judge.Queued(), within) << threads;
    }
  }
}

// A pose whose grasp face runs out of the image but whose face centre and
// some of each side are in view goes on to refinement when a face measured
// on every side may leave the view (the final check then decides); with
// that rule off, the first look drops it, as before; and so it does, rule
// or not, when a whole side is out of view (that side cannot be measured),
// unless the face may run out of view on one side
// (AcceptanceOptions::face_may_run_out_of_view).
// With the principal point at u = 64 the face's far-left corner lies at
// u = -24 and its left side's upper quarter point at u = 3; at u = 30 the
// whole left side is out.
TEST(HypothesisJudgeTest, AFaceLeavingTheViewIsRefinedWhenItMayBeMeasuredThere) {
  const RenderedDepth out_a_side = RenderOneBox(/*cx=*/30.0);
  for (const bool may_leave : {true, false}) {
    for (const bool may_run_out : {true, false}) {
      DetectorOptions o;
      o.box = kCartonS;
      o.acceptance.measured_face_may_leave_view = may_leave;
      o.acceptance.face_may_run_out_of_view = may_run_out;
      internal::HypothesisJudge judge(out_a_side.depth, o);
      judge.Propose(out_a_side.out.boxes.at(0).camera_T_box, 0, {});
      judge.Evaluate(1);
      // A face with one side out of view and its middle in view may be
      // pinned up to the border (internal/border_faces.h): refined.
      EXPECT_EQ(judge.stats().refined, may_leave && may_run_out ? 1 : 0) << may_leave;
    }
  }
  const RenderedDepth b = RenderOneBox(/*cx=*/64.0);
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

// A row of two cartons and a longer box touching end to end with no gap
// (1.0 m: no whole number of cartons), and 4 mm beside it a row of two
// cartons; no noise. No seam between the boxes of the first row, so the
// hypothesis at either carton there finds its face running on flat, and a
// seam along the other row. Proposed as a neighbour of a box accepted and
// declined, it is a stepping stone (its neighbours are still worth
// judging), one step past the last box accepted; proposed otherwise (a
// corner's hypothesis), or with no steps allowed, it is not. Proposed by a
// stepping stone, it is one again while the steps allow.
TEST(HypothesisJudgeTest, ANeighbourRunningOnFlatIsASteppingStone) {
  Scene scene;
  scene.world_T_camera = LookAtCamera(Eigen::Vector3d::Zero(), 1.3, 10.0, 20.0, 0.0);
  auto add = [&](const BoxDims& dims, double x, double y) {
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.translation() = Eigen::Vector3d(x, y, dims.h / 2.0);
    scene.boxes.push_back({dims, pose, true});
  };
  add(kCartonS, -0.3, 0.0);
  add(kCartonS, 0.0, 0.0);
  add(BoxDims{0.40, kCartonS.b, kCartonS.h}, 0.35, 0.0);
  add(kCartonS, -0.3, kCartonS.b + 0.004);
  add(kCartonS, 0.0, kCartonS.b + 0.004);
  const RenderedDepth rendered = RenderNoiseFree(scene);
  const RenderedScene& out = rendered.out;
  const DepthImage& depth = rendered.depth;
  const Eigen::Isometry3d& first = out.boxes.at(0).camera_T_box;
  const Eigen::Isometry3d& second = out.boxes.at(1).camera_T_box;
  auto runs_on_flat = [](const DeclinedCandidate& d) {
    return d.reason.rfind("a side runs on flat", 0) == 0;
  };
  for (const int steps : {2, 1, 0}) {
    DetectorOptions o;
    o.box = kCartonS;
    o.neighbour_steps_past_declined = steps;
    o.turned_proposals = false;  // only the hypotheses proposed here
    // A corner's hypothesis: declined, no stepping stone.
    {
      internal::HypothesisJudge judge(depth, o);
      judge.Propose(first, 0, {});
      EXPECT_TRUE(judge.Evaluate(1).empty());
      ASSERT_EQ(judge.declined().size(), 1u);
      EXPECT_TRUE(runs_on_flat(judge.declined()[0])) << judge.declined()[0].reason;
      EXPECT_TRUE(judge.TakeSteppingStones().empty());
    }
    internal::HypothesisJudge judge(depth, o);
    judge.ProposeNeighbour(first);
    EXPECT_TRUE(judge.Evaluate(1).empty());
    ASSERT_EQ(judge.declined().size(), 1u);
    EXPECT_TRUE(runs_on_flat(judge.declined()[0])) << judge.declined()[0].reason;
    const auto stones = judge.TakeSteppingStones();
    ASSERT_EQ(stones.size(), steps > 0 ? 1u : 0u) << steps;
    EXPECT_TRUE(judge.TakeSteppingStones().empty());  // taken
    if (steps == 0) continue;
    EXPECT_EQ(stones[0].steps, 1);
    EXPECT_EQ(stones[0].box.grasp_face, out.boxes.at(0).grasp_face);
    EXPECT_LT((stones[0].box.camera_T_box.translation() - first.translation()).norm(), 0.01);
    // The other carton, proposed past it: declined alike; a stepping stone
    // two steps past only when two are allowed.
    judge.ProposePastDeclined(second, stones[0].steps);
    EXPECT_TRUE(judge.Evaluate(1).empty());
    ASSERT_EQ(judge.declined().size(), 2u);
    EXPECT_TRUE(runs_on_flat(judge.declined()[1])) << judge.declined()[1].reason;
    const auto next = judge.TakeSteppingStones();
    ASSERT_EQ(next.size(), steps >= 2 ? 1u : 0u) << steps;
    if (steps >= 2) {
      EXPECT_EQ(next[0].steps, 2);
    }
  }
}

// One row only (two cartons end to end, no gap, nothing beside them): the
// hypothesis at either runs on flat with no seam anywhere, a face no
// layer of touching boxes bounds (a bigger face, the floor), and is no
// stepping stone.
TEST(HypothesisJudgeTest, ANeighbourWithNoSeamIsNoSteppingStone) {
  Scene scene;
  scene.world_T_camera = LookAtCamera(Eigen::Vector3d::Zero(), 1.3, 10.0, 20.0, 0.0);
  for (const double x : {-kCartonS.l / 2, kCartonS.l / 2}) {
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.translation() = Eigen::Vector3d(x, 0.0, kCartonS.h / 2.0);
    scene.boxes.push_back({kCartonS, pose, true});
  }
  const RenderedDepth rendered = RenderNoiseFree(scene);
  const RenderedScene& out = rendered.out;
  const DepthImage& depth = rendered.depth;
  DetectorOptions o;
  o.box = kCartonS;
  internal::HypothesisJudge judge(depth, o);
  judge.ProposeNeighbour(out.boxes.at(0).camera_T_box);
  EXPECT_TRUE(judge.Evaluate(1).empty());
  ASSERT_EQ(judge.declined().size(), 1u);
  EXPECT_EQ(judge.declined()[0].reason.rfind("a side runs on flat", 0), 0u)
      << judge.declined()[0].reason;
  EXPECT_TRUE(judge.TakeSteppingStones().empty());
}

// A carton in a layer of touching ones with a small box standing over one
// of its sides: three seams and a hidden side, no free one, so it is
// declined "not boxed in by seams on all four". Proposed as a neighbour, it
// is a stepping stone as one running on flat is: it lies in the layer, and
// the cartons past it are still worth judging.
TEST(HypothesisJudgeTest, ANeighbourNotBoxedInIsASteppingStone) {
  Scene scene;
  scene.world_T_camera = LookAtCamera(Eigen::Vector3d::Zero(), 1.3, 10.0, 20.0, 0.0);
  auto add = [&](const BoxDims& dims, double x, double y, double z) {
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.translation() = Eigen::Vector3d(x, y, z);
    scene.boxes.push_back({dims, pose, true});
  };
  const double gap = 0.004;
  for (int i = -1; i <= 1; ++i) {
    for (int j = -1; j <= 1; ++j) {
      add(kCartonS, i * (kCartonS.l + gap), j * (kCartonS.b + gap), kCartonS.h / 2.0);
    }
  }
  const BoxDims small{0.10, 0.10, 0.10};
  add(small, (kCartonS.l + gap) / 2.0, 0.0, kCartonS.h + small.h / 2.0);
  const RenderedDepth rendered = RenderNoiseFree(scene);
  const RenderedScene& out = rendered.out;
  const DepthImage& depth = rendered.depth;
  DetectorOptions o;
  o.box = kCartonS;
  internal::HypothesisJudge judge(depth, o);
  judge.ProposeNeighbour(out.boxes.at(4).camera_T_box);  // the middle one
  EXPECT_TRUE(judge.Evaluate(1).empty());
  ASSERT_EQ(judge.declined().size(), 1u);
  EXPECT_EQ(judge.declined()[0].reason, "no free side and not boxed in by seams on all four");
  const auto stones = judge.TakeSteppingStones();
  ASSERT_EQ(stones.size(), 1u);
  EXPECT_EQ(stones[0].steps, 1);
}

// A refined face read free on every side but `unseen` (kUnknown: nothing
// on the plane just inside it).
RefinementResult ReadWithOneUnseenSide(int unseen) {
  RefinementResult ref;
  ref.ok = true;
  ref.sides = {SideKind::kFree, SideKind::kFree, SideKind::kFree, SideKind::kFree};
  ref.sides[unseen] = SideKind::kUnknown;
  ref.free_sides = 3;
  return ref;
}

// A carton_s top hidden on two sides across each other (+a, +b occluded:
// a box in front at that corner) could be the face turned a quarter, 0.30
// along b: with the turned check to judge that reading at the corner of
// the two free sides (AcceptanceOptions::turned_hidden_corner_to_check),
// the verdict leaves it to the check; without it, or with one of those two
// sides not measured, the box is declined.
TEST(RefinementVerdictTest, AFaceHiddenOnTwoSidesAcrossIsLeftToTheTurnedCheck) {
  constexpr BoxDims kCartonS{0.30, 0.20, 0.15};
  RefinementResult ref;
  ref.ok = true;
  ref.sides = {SideKind::kOccluded, SideKind::kFree, SideKind::kOccluded, SideKind::kFree};
  ref.free_sides = 2;
  AcceptanceOptions o;
  EXPECT_EQ(internal::RefinementVerdict(ref, kCartonS, BoxFace::kPlusZ, o), "");
  o.turned_hidden_corner_to_check = false;
  EXPECT_EQ(internal::RefinementVerdict(ref, kCartonS, BoxFace::kPlusZ, o),
            "a hidden side could be a longer side of the box");
  // A seam and a free side make the corner too; one side tiled does not.
  o.turned_hidden_corner_to_check = true;
  ref.sides[1] = SideKind::kSeam;
  ref.free_sides = 1;
  EXPECT_EQ(internal::RefinementVerdict(ref, kCartonS, BoxFace::kPlusZ, o), "");
  ref.sides[1] = SideKind::kTiled;
  EXPECT_EQ(internal::RefinementVerdict(ref, kCartonS, BoxFace::kPlusZ, o),
            "a hidden side could be a longer side of the box");
}

// A side with no point just inside it whose pixels see behind the plane
// (RefinementResult::seen_through): the face ends before it, whatever the
// other sides say; not where the side is out of view.
TEST(RefinementVerdictTest, ASideSeenThroughDeclinesTheReading) {
  constexpr BoxDims kCartonSq{0.25, 0.25, 0.20};
  RefinementResult ref = ReadWithOneUnseenSide(3);
  AcceptanceOptions o;
  EXPECT_EQ(internal::RefinementVerdict(ref, kCartonSq, BoxFace::kPlusZ, o), "");
  ref.seen_through[3] = true;
  EXPECT_EQ(internal::RefinementVerdict(ref, kCartonSq, BoxFace::kPlusZ, o)
                .rfind("the face is seen through just inside a side", 0),
            0u);
  EXPECT_EQ(internal::RefinementVerdict(ref, kCartonSq, BoxFace::kPlusZ, o, /*out_of_view_side=*/3),
            "");
}

// A side with nothing seen near it (kUnknown: a shadow) may hide more face,
// as an occluded one does: a square carton read on a 0.25 x 0.20 side face
// whose 0.20 side is unseen could as well be lying flat, its 0.25 x 0.25
// top running on into the shadow.
TEST(RefinementVerdictTest, AnUnseenSideWhereALongerSideCouldStandIsDeclined) {
  constexpr BoxDims kCartonSq{0.25, 0.25, 0.20};
  // +y face: its a axis is the box's z (0.20), its b axis the box's x (0.25).
  RefinementResult ref = ReadWithOneUnseenSide(0);
  AcceptanceOptions o;
  EXPECT_EQ(internal::RefinementVerdict(ref, kCartonSq, BoxFace::kPlusY, o),
            "a hidden side could be a longer side of the box");
  o.check_unseen_sides = false;
  EXPECT_EQ(internal::RefinementVerdict(ref, kCartonSq, BoxFace::kPlusY, o), "");
  // On the 0.25 axis of the top face no longer side could stand in.
  o.check_unseen_sides = true;
  EXPECT_EQ(internal::RefinementVerdict(ref, kCartonSq, BoxFace::kPlusZ, o), "");
  // A carton_s top (0.30 x 0.20) unseen at one end of its 0.20 axis: its
  // 0.30 axis, free at both ends, pins the reading ...
  ref.sides = {SideKind::kFree, SideKind::kFree, SideKind::kUnknown, SideKind::kFree};
  EXPECT_EQ(internal::RefinementVerdict(ref, kCartonS, BoxFace::kPlusZ, o), "");
  // ... and a side across it unseen too leaves it pinned by the free ones
  // (a turned reading needs them the other size apart).
  ref.sides = {SideKind::kUnknown, SideKind::kFree, SideKind::kUnknown, SideKind::kFree};
  ref.free_sides = 2;
  EXPECT_EQ(internal::RefinementVerdict(ref, kCartonS, BoxFace::kPlusZ, o), "");
}

// A face measured between free sides on both axes and short of the box on
// both by more than max_short_both_axes_m is a smaller box whose top is
// within the extent tolerance of this box's face each way (a 0.18 x 0.13 m
// distractor read as a carton_s on its 0.20 x 0.15 end). Short on one axis
// only (a crushed corner), or by less, it is the box.
TEST(RefinementVerdictTest, AFaceShortOfTheBoxBothWaysIsASmallerBox) {
  RefinementResult ref;
  ref.ok = true;
  ref.sides = {SideKind::kFree, SideKind::kFree, SideKind::kFree, SideKind::kFree};
  ref.free_sides = 4;
  // +x face: its a axis is the box's y (0.20), its b axis the box's z (0.15).
  ref.extent_a_m = 0.186;
  ref.extent_b_m = 0.128;
  AcceptanceOptions o;
  EXPECT_EQ(internal::RefinementVerdict(ref, kCartonS, BoxFace::kPlusX, o)
                .rfind("face measures 0.186 x 0.128 m, short of the box's 0.200 x 0.150 m", 0),
            0u);
  ref.extent_a_m = 0.195;  // one axis within 12 mm
  EXPECT_EQ(internal::RefinementVerdict(ref, kCartonS, BoxFace::kPlusX, o), "");
  ref.extent_a_m = 0.186;
  ref.extent_b_m = 0.0;  // the b axis not measured between free sides
  EXPECT_EQ(internal::RefinementVerdict(ref, kCartonS, BoxFace::kPlusX, o), "");
  ref.extent_b_m = 0.128;
  o.max_short_both_axes_m = 0.0;  // off
  EXPECT_EQ(internal::RefinementVerdict(ref, kCartonS, BoxFace::kPlusX, o), "");
  o.max_short_both_axes_m = -0.01;
  EXPECT_NE(o.Validate().message().find("acceptance.max_short_both_axes_m"), std::string::npos);
}

// The longer reading under side 2 of a carton_s read on its +x end face
// (0.20 x 0.15; side 2 ends its 0.15 axis): the face runs on from side 3
// to the box's third side (0.30), the box 0.15 deep behind it.
TEST(LongerUnderSideTest, TheFaceRunsOnFromTheOppositeSideToTheThirdSide) {
  const Eigen::Isometry3d pose = Eigen::Translation3d(0.1, -0.2, 1.5) *
                                 Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 2, 3).normalized());
  // +x face: a is the box's y, b its z; side 2 lies at +z.
  const Eigen::Isometry3d longer = internal::LongerUnderSide(pose, BoxFace::kPlusX, kCartonS, 2);
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e9), hi = -lo;
  for (const Eigen::Vector3d& c : BoxCorners(longer, kCartonS)) {
    const Eigen::Vector3d in_box = pose.inverse() * c;
    lo = lo.cwiseMin(in_box);
    hi = hi.cwiseMax(in_box);
  }
  EXPECT_NEAR(hi.x(), 0.15, 1e-9);   // the face's plane
  EXPECT_NEAR(lo.x(), 0.0, 1e-9);    // 0.15 deep
  EXPECT_NEAR(lo.y(), -0.10, 1e-9);  // the other axis as it was
  EXPECT_NEAR(hi.y(), 0.10, 1e-9);
  EXPECT_NEAR(lo.z(), -0.075, 1e-9);  // from side 3 ...
  EXPECT_NEAR(hi.z(), 0.225, 1e-9);   // ... 0.30 on past side 2
}

// A brick standing on its long edge, its top (0.19 x 0.057) read with one
// 0.057 side unseen: a brick lying on its side, its 0.19 x 0.09 face running
// on 3.3 cm there, could stand in, and the reading is declined. Past that
// side the camera sees the floor 9 cm below where that face would be: the
// depth rules the longer reading out (AcceptanceOptions::
// unseen_longer_see_through) and the reading stands. A block as tall as
// the longer reading standing against that side leaves it possible.
TEST(RefinementVerdictTest, AnUnseenSideWhoseLongerReadingIsSeenThroughLeavesNoDoubt) {
  constexpr BoxDims kBrick{0.19, 0.09, 0.057};
  const BoxDims block{0.19, 0.04, 0.09};
  Scene scene;
  scene.world_T_camera = LookAtCamera(Eigen::Vector3d::Zero(), 1.0, 10.0, 20.0, 0.0);
  Eigen::Isometry3d on_edge(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitX()));
  on_edge.translation().z() = kBrick.b / 2.0;  // the box's y up, its z along -y
  scene.boxes.push_back({kBrick, on_edge, true});
  const RenderedDepth alone = RenderNoiseFree(scene);
  Eigen::Isometry3d beside = Eigen::Isometry3d::Identity();
  beside.translation() =
      Eigen::Vector3d(0.0, -kBrick.h / 2.0 - 0.001 - block.b / 2.0, block.h / 2.0);
  scene.boxes.push_back({block, beside, false});
  const RenderedDepth with_block = RenderNoiseFree(scene);

  const GroundTruthBox& gt = alone.out.boxes.at(0);
  ASSERT_EQ(static_cast<int>(gt.grasp_face) / 2, 1) << "the box's y face up";
  // The face's a axis is the box's z: side 0 lies at +z, over the block.
  const RefinementResult ref = ReadWithOneUnseenSide(0);
  DetectorOptions o;
  o.box = kBrick;
  EXPECT_EQ(internal::RefinementVerdict(ref, kBrick, gt.grasp_face, o.acceptance),
            "a hidden side could be a longer side of the box");
  const unsigned ruled_out =
      internal::LongerReadingsRuledOut(alone.depth, gt.camera_T_box, gt.grasp_face, ref, o);
  EXPECT_EQ(ruled_out, 1u);
  EXPECT_EQ(internal::RefinementVerdict(ref, kBrick, gt.grasp_face, o.acceptance, -1, ruled_out),
            "");
  EXPECT_EQ(internal::LongerReadingsRuledOut(
                with_block.depth, with_block.out.boxes.at(0).camera_T_box, gt.grasp_face, ref, o),
            0u);
  o.acceptance.unseen_longer_see_through = 0.0;
  EXPECT_EQ(internal::LongerReadingsRuledOut(alone.depth, gt.camera_T_box, gt.grasp_face, ref, o),
            0u);
}

// A pair may end each other (AcceptanceOptions::pairs_end_each_other) only
// when each runs on flat on one side and is ended on the three others.
TEST(OneSideOnFlatTest, OneSideOnFlatAndTheOthersEnded) {
  RefinementResult ref;
  ref.sides = {SideKind::kContinues, SideKind::kFree, SideKind::kSeam, SideKind::kTiled};
  EXPECT_TRUE(internal::OneSideOnFlat(ref));
  ref.sides[1] = SideKind::kContinues;
  EXPECT_FALSE(internal::OneSideOnFlat(ref));  // two on flat
  ref.sides[1] = SideKind::kUnknown;
  EXPECT_FALSE(internal::OneSideOnFlat(ref));  // one not ended
  ref.sides[1] = SideKind::kOccluded;
  EXPECT_FALSE(internal::OneSideOnFlat(ref));
  ref.sides = {SideKind::kFree, SideKind::kFree, SideKind::kSeam, SideKind::kSeam};
  EXPECT_FALSE(internal::OneSideOnFlat(ref));  // none on flat
}

}  // namespace
}  // namespace cornerpose::testing
