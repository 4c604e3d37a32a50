// The programs RenderPickProgram writes are inside the URScript subset the
// UR controller emulator (tests/support/ur_emulator) compiles: its parser
// accepts them and reads back the statements, targets and outputs planned.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "robot_client/planning/urscript_program.h"
#include "robot_client/ur/pose.h"
#include "tests/robot_client/test_poses.h"
#include "tests/support/ur_emulator/urscript.h"

namespace cornerpose::robot_client {
namespace {

using testing::ToolDownAt;

TEST(UrscriptEmulatorParseTest, EmulatorCompilesTheProgramAsPlanned) {
  for (bool standard : {false, true}) {
    SCOPED_TRACE(standard);
    PickPlan plan;
    plan.grasp = ToolDownAt(0.1, -0.5, 0.15, 0.4);
    plan.approach = ToolDownAt(0.1, -0.5, 0.25, 0.4);
    plan.retrieve = ToolDownAt(0.1, -0.5, 0.40, 0.4);
    plan.place = ToolDownAt(-0.32, 0.4, 0.15, -2.9);
    plan.place_above = ToolDownAt(-0.32, 0.4, 0.25, -2.9);
    GripperOptions gripper;
    gripper.flange_T_tcp.translation() = Eigen::Vector3d(0, 0, 0.1);
    gripper.suction_output = standard ? SuctionOutputKind::kStandard : SuctionOutputKind::kTool;
    gripper.suction_output_index = standard ? 5 : 1;
    const ur::Joints clear = {-1.9615, -1.8673, 1.3887, -1.0921, -1.5708, -0.3907};
    absl::StatusOr<std::string> text =
        RenderPickProgram("pick_0042", plan, gripper, MotionOptions(), clear);
    ASSERT_TRUE(text.ok()) << text.status();

    const ur_emulator::ParseResult parsed = ur_emulator::ParseScript(*text);
    ASSERT_FALSE(parsed.error.has_value())
        << parsed.error->text << " at line " << parsed.error->line;
    EXPECT_EQ(parsed.program.name, "pick_0042");
    const std::string out = standard ? "set_standard_digital_out" : "set_tool_digital_out";
    const std::vector<std::string> expected = {"set_tcp", "textmsg", "movej", "movel",  out,
                                               "sleep",   "movel",   "movej", "movel",  out,
                                               "sleep",   "movel",   "movej", "textmsg"};
    ASSERT_EQ(parsed.program.calls.size(), expected.size());
    for (size_t i = 0; i < expected.size(); ++i) {
      EXPECT_EQ(parsed.program.calls[i].function, expected[i]) << i;
    }
    // The free moves' targets are the planned joints: M's, place_above's.
    const std::pair<size_t, const ur::Joints*> joint_moves[] = {{2, &plan.approach_joints},
                                                                {7, &plan.place_above_joints}};
    for (const auto& [index, joints] : joint_moves) {
      const ur_emulator::ScriptValue& q = parsed.program.calls[index].arg("q");
      ASSERT_EQ(q.kind, ur_emulator::ScriptValue::Kind::kList) << index;
      ASSERT_EQ(q.elements.size(), 6u);
      for (size_t i = 0; i < 6; ++i) EXPECT_NEAR(q.elements[i], (*joints)[i], 1e-6) << index;
    }
    // Pose targets, in order: G, R, F, place_above.
    const Eigen::Isometry3d* targets[] = {&plan.grasp, &plan.retrieve, &plan.place,
                                          &plan.place_above};
    const size_t moves[] = {3, 6, 8, 11};
    for (size_t k = 0; k < 4; ++k) {
      const ur_emulator::ScriptCall& call = parsed.program.calls[moves[k]];
      const ur_emulator::ScriptValue& target = call.arg("pose");
      ASSERT_EQ(target.kind, ur_emulator::ScriptValue::Kind::kPose) << k;
      ASSERT_EQ(target.elements.size(), 6u);
      const ur::UrPose pose{
          Eigen::Vector3d(target.elements[0], target.elements[1], target.elements[2]),
          Eigen::Vector3d(target.elements[3], target.elements[4], target.elements[5])};
      const Eigen::Isometry3d back = ur::FromUrPose(pose);
      EXPECT_LT((back.translation() - targets[k]->translation()).norm(), 1e-6) << k;
      EXPECT_LT(ur::RotationAngleBetween(Eigen::Quaterniond(back.linear()),
                                         Eigen::Quaterniond(targets[k]->linear())),
                1e-5)
          << k;
    }
    // Vacuum on after G, off after F, on the configured output.
    EXPECT_EQ(parsed.program.calls[4].arg("n").number, gripper.suction_output_index);
    EXPECT_TRUE(parsed.program.calls[4].arg("b").boolean);
    EXPECT_FALSE(parsed.program.calls[9].arg("b").boolean);
    // The clear move is a joint vector.
    const ur_emulator::ScriptValue& q = parsed.program.calls[12].arg("q");
    ASSERT_EQ(q.kind, ur_emulator::ScriptValue::Kind::kList);
    ASSERT_EQ(q.elements.size(), 6u);
    for (int i = 0; i < 6; ++i) EXPECT_NEAR(q.elements[i], clear[i], 1e-6);
  }
}

}  // namespace
}  // namespace cornerpose::robot_client
