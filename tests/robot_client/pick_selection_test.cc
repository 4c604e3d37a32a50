// SelectPick: rejections with reasons (score, tilt, workspace,
// reachability), topmost first with a height tolerance, then score.
#include "robot_client/planning/pick_selection.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace cornerpose::robot_client {
namespace {

using ::testing::HasSubstr;

const BoxDims kCarton{0.30, 0.20, 0.15};

// A flat carton whose top face (+z, the grasp face) is at height top_z.
DetectedBox Box(double x, double y, double top_z, double score) {
  DetectedBox box;
  box.camera_T_box.translation() = Eigen::Vector3d(x, y, top_z - 0.075);
  box.grasp_face = BoxFace::kPlusZ;
  box.score = score;
  return box;
}

// A carton the detector took on its side (+y up: 0.20 m deep), its top at
// 0.30 m like Box(0.35, -0.25, 0.30, ...).
DetectedBox OnItsSide() {
  DetectedBox side;
  side.camera_T_box.translation() = Eigen::Vector3d(0.35, -0.25, 0.30 - 0.10);
  side.camera_T_box.linear() =
      Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitX()).toRotationMatrix();
  side.grasp_face = BoxFace::kPlusY;
  side.score = 0.99;
  return side;
}

class PickSelectionTest : public ::testing::Test {
 protected:
  PickSelection Select(const std::vector<DetectedBox>& boxes,
                       const Reachability& reachable = nullptr) {
    // The boxes are given in the base frame: base_T_camera = identity.
    return SelectPick(boxes, Eigen::Isometry3d::Identity(), kCarton, selection_, workspace_,
                      waypoints_, reachable);
  }

  SelectionOptions selection_;  // 30 deg, score >= 0, ties within 1 cm
  WaypointOptions waypoints_;   // d 0.10, h 0.25
  Workspace workspace_{Eigen::Vector3d(-0.6, -0.9, 0.03), Eigen::Vector3d(0.6, 0.8, 0.9)};
};

TEST_F(PickSelectionTest, NoBoxesNoChoice) {
  const PickSelection s = Select({});
  EXPECT_FALSE(s.chosen.has_value());
  EXPECT_TRUE(s.verdicts.empty());
}

TEST_F(PickSelectionTest, TiltedFaceIsRejected) {
  DetectedBox tilted = Box(0, -0.5, 0.15, 0.9);
  tilted.camera_T_box.linear() =
      Eigen::AngleAxisd(40.0 * M_PI / 180.0, Eigen::Vector3d::UnitX()).toRotationMatrix();
  DetectedBox slight = Box(0.35, -0.5, 0.15, 0.5);
  slight.camera_T_box.linear() =
      Eigen::AngleAxisd(20.0 * M_PI / 180.0, Eigen::Vector3d::UnitY()).toRotationMatrix();
  const PickSelection s = Select({tilted, slight});
  ASSERT_EQ(s.verdicts.size(), 2u);
  EXPECT_FALSE(s.verdicts[0].accepted);
  EXPECT_THAT(s.verdicts[0].reason, HasSubstr("tilted 40.0 deg"));
  EXPECT_NEAR(s.verdicts[0].box.tilt_deg, 40.0, 1e-6);
  EXPECT_TRUE(s.verdicts[1].accepted) << s.verdicts[1].reason;
  EXPECT_EQ(s.chosen, 1);
}

TEST_F(PickSelectionTest, OutsideTheWorkspaceIsRejected) {
  // One too far out in x; one whose R (0.75 + 0.25) is above the workspace.
  const PickSelection s = Select({Box(0.9, -0.5, 0.15, 0.9), Box(0, -0.5, 0.75, 0.9)});
  ASSERT_EQ(s.verdicts.size(), 2u);
  EXPECT_FALSE(s.chosen.has_value());
  EXPECT_THAT(s.verdicts[0].reason, HasSubstr("grasp point G"));
  EXPECT_THAT(s.verdicts[0].reason, HasSubstr("outside the workspace"));
  EXPECT_THAT(s.verdicts[1].reason, HasSubstr("retrieve point R"));
}

TEST_F(PickSelectionTest, UnreachableIsRejected) {
  // Nothing beyond 0.4 m from the base axis is reachable.
  const Reachability near_base = [](const Eigen::Isometry3d& T) {
    return T.translation().head<2>().norm() < 0.4;
  };
  const PickSelection s =
      Select({Box(0.0, -0.5, 0.15, 0.99), Box(0.0, -0.3, 0.15, 0.2)}, near_base);
  EXPECT_FALSE(s.verdicts[0].accepted);
  EXPECT_THAT(s.verdicts[0].reason, HasSubstr("not reachable"));
  EXPECT_TRUE(s.verdicts[1].accepted);
  EXPECT_EQ(s.chosen, 1);

  const Reachability nothing = [](const Eigen::Isometry3d&) { return false; };
  EXPECT_FALSE(Select({Box(0.0, -0.3, 0.15, 0.2)}, nothing).chosen.has_value());
}

TEST_F(PickSelectionTest, LowScoreIsRejected) {
  selection_.min_score = 0.5;
  const PickSelection s = Select({Box(0, -0.5, 0.30, 0.4), Box(0.2, -0.5, 0.15, 0.6)});
  EXPECT_THAT(s.verdicts[0].reason, HasSubstr("below min_score"));
  EXPECT_EQ(s.chosen, 1);  // lower, but the only one accepted
}

TEST_F(PickSelectionTest, TopmostFirstThenScore) {
  // Layers 1 cm thick here, so E below is not in B's and C's layer (a layer
  // of three takes its median top: ALayerOfThreeSharesItsMedianTop).
  selection_.layer_tolerance_m = 0.01;
  // B is clearly the highest.
  EXPECT_EQ(Select({Box(0, -0.5, 0.15, 0.9), Box(0.2, -0.5, 0.30, 0.5)}).chosen, 1);
  // C is 5 mm above B: a tie, decided by C's higher score; D, 7 mm below C,
  // ties with C too and scores higher still.
  const std::vector<DetectedBox> boxes = {Box(0, -0.5, 0.15, 0.99), Box(0.2, -0.5, 0.300, 0.5),
                                          Box(-0.2, -0.5, 0.305, 0.8)};
  EXPECT_EQ(Select(boxes).chosen, 2);
  std::vector<DetectedBox> with_d = boxes;
  with_d.push_back(Box(0.2, -0.7, 0.298, 0.95));
  EXPECT_EQ(Select(with_d).chosen, 3);
  // A box 2 cm lower does not tie, however good its score.
  std::vector<DetectedBox> with_e = boxes;
  with_e.push_back(Box(0.2, -0.7, 0.285, 1.0));
  EXPECT_EQ(Select(with_e).chosen, 2);
  // Equal heights and scores: the first.
  EXPECT_EQ(Select({Box(0, -0.5, 0.15, 0.7), Box(0.35, -0.5, 0.15, 0.7)}).chosen, 0);
}

TEST_F(PickSelectionTest, RankedListsTheAcceptedBoxesBestFirst) {
  // A 0.15 (0.9), B 0.300 (0.5), C 0.305 (0.8), D rejected (tilted), E 0.15
  // (0.95), F 0.297 (0.5, ties with B on everything but height).
  DetectedBox d = Box(0.1, -0.6, 0.40, 0.99);
  d.camera_T_box.linear() =
      Eigen::AngleAxisd(50.0 * M_PI / 180.0, Eigen::Vector3d::UnitX()).toRotationMatrix();
  const PickSelection s =
      Select({Box(0, -0.5, 0.15, 0.9), Box(0.2, -0.5, 0.300, 0.5), Box(-0.2, -0.5, 0.305, 0.8), d,
              Box(0.2, -0.7, 0.15, 0.95), Box(-0.2, -0.7, 0.297, 0.5)});
  ASSERT_TRUE(s.chosen.has_value());
  EXPECT_FALSE(s.verdicts[3].accepted);
  // C wins the top tie; then B and F tie (B higher); then the table level,
  // where E's score beats A's.
  EXPECT_EQ(s.ranked, (std::vector<int>{2, 1, 5, 4, 0}));
  EXPECT_EQ(s.chosen, s.ranked.front());
  // Nothing accepted: nothing ranked.
  selection_.min_score = 0.999;
  const PickSelection none = Select({Box(0, -0.5, 0.15, 0.9)});
  EXPECT_TRUE(none.ranked.empty());
  EXPECT_FALSE(none.chosen.has_value());
}

TEST_F(PickSelectionTest, BoxesGoThroughTheHandEyeCalibration) {
  // The camera 1.1 m up looking down; a box 0.95 m in front of it is on the
  // table (top at 0.15).
  Eigen::Isometry3d base_T_camera = Eigen::Isometry3d::Identity();
  base_T_camera.linear() = Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX()).toRotationMatrix();
  base_T_camera.translation() = Eigen::Vector3d(0, -0.5, 1.1);
  DetectedBox seen;
  seen.camera_T_box.translation() = Eigen::Vector3d(0.05, 0.0, 1.025);
  seen.camera_T_box.linear() =
      Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX()).toRotationMatrix();  // box z up
  seen.grasp_face = BoxFace::kPlusZ;
  seen.score = 0.8;
  const PickSelection s =
      SelectPick({seen}, base_T_camera, kCarton, selection_, workspace_, waypoints_, nullptr);
  ASSERT_EQ(s.chosen, 0) << s.verdicts[0].reason;
  EXPECT_TRUE(s.verdicts[0].box.grasp_point.isApprox(Eigen::Vector3d(0.05, -0.5, 0.15), 1e-9));
  EXPECT_NEAR(s.verdicts[0].box.tilt_deg, 0.0, 1e-6);
}

}  // namespace
}  // namespace cornerpose::robot_client

namespace cornerpose::robot_client {
namespace {

TEST_F(PickSelectionTest, BoxesSharingSpaceInALayerAreDeclined) {
  // Two cartons of one layer 0.20 m apart along their 0.30 m length: 0.10 m
  // of overlap, so one is misplaced (a centre off along the length); both are
  // declined. A third, clear of both, is picked.
  const PickSelection s =
      Select({Box(0.0, -0.5, 0.15, 0.9), Box(0.2, -0.5, 0.15, 0.9), Box(0.0, -0.25, 0.15, 0.5)});
  ASSERT_EQ(s.verdicts.size(), 3u);
  EXPECT_THAT(s.verdicts[0].reason, HasSubstr("overlaps box #1 of its layer by 0.100 m"));
  EXPECT_THAT(s.verdicts[1].reason, HasSubstr("overlaps box #0"));
  EXPECT_TRUE(s.verdicts[2].accepted) << s.verdicts[2].reason;
  EXPECT_EQ(s.chosen, 2);
  // A looser max_overlap_m lets them both through.
  selection_.max_overlap_m = 0.11;
  EXPECT_EQ(Select({Box(0.0, -0.5, 0.15, 0.9), Box(0.2, -0.5, 0.15, 0.9)}).ranked.size(), 2u);
}

TEST_F(PickSelectionTest, WrongFaceSizeInALayerIsDeclined) {
  // Three cartons lying flat (+z up: 0.15 m deep) and one the detector took
  // on its side (+y up: 0.20 m deep) with its top at the same height.
  std::vector<DetectedBox> boxes = {Box(0.0, -0.5, 0.30, 0.9), Box(0.35, -0.5, 0.30, 0.9),
                                    Box(0.0, -0.25, 0.30, 0.9)};
  const DetectedBox side = OnItsSide();
  boxes.push_back(side);
  const PickSelection s = Select(boxes);
  ASSERT_EQ(s.verdicts.size(), 4u);
  EXPECT_NEAR(s.verdicts[3].box.depth_m, 0.20, 1e-9);
  EXPECT_THAT(s.verdicts[3].reason, HasSubstr("3 of the 4 boxes in view"));
  EXPECT_THAT(s.verdicts[3].reason, HasSubstr("the wrong face size"));
  EXPECT_EQ(s.ranked.size(), 3u);
  // With the check off, it is the best box.
  selection_.min_layer_for_face_check = 0;
  EXPECT_EQ(Select(boxes).chosen, 3);
}

TEST_F(PickSelectionTest, TheLastPicksVoteOnTheFaceWhenFewBoxesAreInView) {
  // The last box of a layer, taken on its side (+y up: 0.20 m deep), alone
  // in view: the frame alone cannot tell; the cell's last picks, all 0.15 m
  // deep, can.
  const DetectedBox side = OnItsSide();
  const std::vector<double> picked(10, 0.15);
  auto select = [&](const std::vector<double>& history) {
    return SelectPick({side}, Eigen::Isometry3d::Identity(), kCarton, selection_, workspace_,
                      waypoints_, nullptr, history);
  };
  // No history configured: chosen.
  EXPECT_EQ(select(picked).chosen, 0);
  selection_.face_check_history = 4;
  const PickSelection s = select(picked);
  EXPECT_FALSE(s.chosen.has_value());
  EXPECT_THAT(
      s.verdicts[0].reason,
      HasSubstr("4 of the 5 boxes in view (1) and last picks (4) show a face 0.150 m deep"));
  // Picks of the same face agree with it.
  EXPECT_EQ(select(std::vector<double>(10, 0.20)).chosen, 0);
  // Too few votes for the check (min_layer_for_face_check 3): one pick.
  EXPECT_EQ(select({0.15}).chosen, 0);
  // Out of range is named.
  selection_.face_check_history = 101;
  EXPECT_THAT(selection_.Validate().message(), HasSubstr("selection.face_check_history"));
}

TEST_F(PickSelectionTest, ALayerOfThreeSharesItsMedianTop) {
  // Tops 0.300, 0.305 and 0.288 (the sensor's depth steps): each grasp point
  // at 0.300; a pair alone keeps its own.
  const PickSelection s = Select(
      {Box(0.0, -0.5, 0.300, 0.9), Box(0.35, -0.5, 0.305, 0.9), Box(0.0, -0.25, 0.288, 0.9)});
  for (const BoxVerdict& v : s.verdicts) EXPECT_NEAR(v.box.grasp_point.z(), 0.300, 1e-9);
  const PickSelection pair = Select({Box(0.0, -0.5, 0.300, 0.9), Box(0.35, -0.5, 0.305, 0.9)});
  EXPECT_NEAR(pair.verdicts[1].box.grasp_point.z(), 0.305, 1e-9);
}

TEST_F(PickSelectionTest, EveryBoxCarriesThePileTop) {
  const PickSelection s = Select({Box(0.0, -0.5, 0.15, 0.9), Box(0.35, -0.5, 0.45, 0.2)});
  for (const BoxVerdict& v : s.verdicts) EXPECT_NEAR(v.box.pile_top_z_m, 0.45, 1e-9);
}

}  // namespace
}  // namespace cornerpose::robot_client
