// The decisions of one pass of the cell's loop (robot_client/cell/cell_steps.h):
// when the cell is finished, which ranked box is planned, and the log lines.
#include "robot_client/cell/cell_steps.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace cornerpose::robot_client {
namespace {

using ::testing::HasSubstr;

TEST(FinishedReasonTest, FullPatternThenMaxPicksThenNotFinished) {
  CellStatusSnapshot status;
  status.num_slots = 4;
  status.next_slot = 4;
  EXPECT_EQ(FinishedReason(status, 0), "the place pattern is full");
  status.next_slot = 2;
  status.picks_done = 2;
  EXPECT_EQ(FinishedReason(status, 2), "made max_picks (2)");
  EXPECT_EQ(FinishedReason(status, 3), std::nullopt);
  // 0 = no limit.
  EXPECT_EQ(FinishedReason(status, 0), std::nullopt);
}

PickSelection ThreeAccepted() {
  PickSelection selection;
  for (int i = 0; i < 3; ++i) {
    BoxVerdict v;
    v.index = i;
    v.accepted = true;
    v.score = 0.5 + 0.1 * i;
    v.box.grasp_point = Eigen::Vector3d(0.1 * i, 0, 0);
    selection.verdicts.push_back(v);
  }
  selection.ranked = {2, 0, 1};
  selection.chosen = 2;
  return selection;
}

TEST(PlanFirstPlannableTest, TakesTheFirstRankedBoxThatPlans) {
  const PickSelection selection = ThreeAccepted();
  std::vector<double> tried;
  PlannedPick planned = PlanFirstPlannable(selection, [&](const BoxInBase& box) {
    tried.push_back(box.grasp_point.x());
    if (box.grasp_point.x() > 0.15)
      return absl::StatusOr<PickPlan>(absl::FailedPreconditionError("singular"));
    return absl::StatusOr<PickPlan>(PickPlan{});
  });
  ASSERT_NE(planned.chosen, nullptr);
  EXPECT_EQ(planned.chosen->index, 0);
  EXPECT_TRUE(planned.plan.ok());
  // Ranked order, stopping at the first plan.
  EXPECT_THAT(tried, ::testing::ElementsAre(0.2, 0.0));
  ASSERT_EQ(planned.refusals.size(), 1u);
  EXPECT_EQ(planned.refusals[0], "#2 singular");
}

TEST(PlanFirstPlannableTest, NoneThatPlansListsEveryRefusal) {
  PlannedPick planned = PlanFirstPlannable(ThreeAccepted(), [](const BoxInBase&) {
    return absl::StatusOr<PickPlan>(absl::FailedPreconditionError("out of reach"));
  });
  EXPECT_EQ(planned.chosen, nullptr);
  EXPECT_FALSE(planned.plan.ok());
  EXPECT_THAT(planned.refusals,
              ::testing::ElementsAre("#2 out of reach", "#0 out of reach", "#1 out of reach"));
}

TEST(DescribeRejectionsTest, NamesEveryBox) {
  EXPECT_EQ(DescribeRejections(PickSelection{}), "no boxes detected");
  PickSelection selection;
  selection.verdicts.resize(2);
  selection.verdicts[0].index = 0;
  selection.verdicts[0].reason = "score 0.1 below 0.5";
  selection.verdicts[1].index = 1;
  selection.verdicts[1].reason = "outside the workspace";
  EXPECT_THAT(
      DescribeRejections(selection),
      HasSubstr("2 boxes, none pickable: #0 score 0.1 below 0.5; #1 outside the workspace"));
}

TEST(NotLiftedTest, ABoxLeftWhereItWasIsDeclinedAndTheRankingMovesOn) {
  PickSelection selection = ThreeAccepted();  // grasp points x = 0, 0.1, 0.2; ranked 2, 0, 1
  // The last pick went to box 2's grasp point, 1 cm off: its box is there.
  EXPECT_TRUE(StillThere(selection, Eigen::Vector3d(0.21, 0, 0), 0.02));
  EXPECT_FALSE(StillThere(selection, Eigen::Vector3d(0.25, 0, 0), 0.02));
  DeclineNotLifted({{Eigen::Vector3d(0.21, 0, 0)}}, 0.02, &selection);
  EXPECT_FALSE(selection.verdicts[2].accepted);
  EXPECT_THAT(selection.verdicts[2].reason, HasSubstr("left this box where it was"));
  EXPECT_EQ(selection.ranked, (std::vector<int>{0, 1}));
  EXPECT_EQ(selection.chosen, 0);
  // Nothing not lifted: nothing changes.
  PickSelection untouched = ThreeAccepted();
  DeclineNotLifted({}, 0.02, &untouched);
  EXPECT_EQ(untouched.chosen, 2);
  EXPECT_EQ(untouched.ranked.size(), 3u);
  // All declined: no choice.
  PickSelection none = ThreeAccepted();
  DeclineNotLifted(
      {{Eigen::Vector3d(0, 0, 0)}, {Eigen::Vector3d(0.1, 0, 0)}, {Eigen::Vector3d(0.2, 0, 0)}},
      0.02, &none);
  EXPECT_FALSE(none.chosen.has_value());
  EXPECT_TRUE(none.ranked.empty());
}

}  // namespace
}  // namespace cornerpose::robot_client
