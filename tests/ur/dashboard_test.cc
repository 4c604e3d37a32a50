#include "robot_client/ur/dashboard.h"

#include <gtest/gtest.h>

namespace cornerpose::ur {
namespace {

TEST(DashboardReplies, RobotMode) {
  EXPECT_EQ(*ParseRobotModeReply("Robotmode: RUNNING"), RobotMode::kRunning);
  EXPECT_EQ(*ParseRobotModeReply("  robotmode:power_off \r"), RobotMode::kPowerOff);
  EXPECT_EQ(*ParseRobotModeReply("Robotmode: NO_CONTROLLER"), RobotMode::kNoController);
  EXPECT_EQ(ParseRobotModeReply("Robotmode: FLYING").status().code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_FALSE(ParseRobotModeReply("could not understand: 'robotmode'").ok());
  EXPECT_FALSE(ParseRobotModeReply("").ok());
}

TEST(DashboardReplies, Safety) {
  EXPECT_EQ(*ParseSafetyReply("Safetystatus: PROTECTIVE_STOP"), SafetyMode::kProtectiveStop);
  EXPECT_EQ(*ParseSafetyReply("Safetymode: NORMAL"), SafetyMode::kNormal);
  EXPECT_EQ(*ParseSafetyReply("Safetystatus: SYSTEM_THREE_POSITION_ENABLING_STOP"),
            SafetyMode::kSystemThreePositionEnablingStop);
  EXPECT_FALSE(ParseSafetyReply("Safetystatus:").ok());
  EXPECT_FALSE(ParseSafetyReply("could not understand: 'safetystatus'").ok());
}

TEST(DashboardReplies, RunningAndProgramState) {
  EXPECT_TRUE(*ParseRunningReply("Program running: true"));
  EXPECT_FALSE(*ParseRunningReply("Program running: false"));
  EXPECT_TRUE(*ParseRunningReply("Robot running: True"));
  EXPECT_FALSE(ParseRunningReply("Program running: maybe").ok());
  absl::StatusOr<ProgramStateReply> p = ParseProgramStateReply("STOPPED wait_program.urp");
  ASSERT_TRUE(p.ok());
  EXPECT_EQ(p->state, ProgramState::kStopped);
  EXPECT_EQ(p->program, "wait_program.urp");
  p = ParseProgramStateReply("PLAYING <unnamed>");
  ASSERT_TRUE(p.ok());
  EXPECT_EQ(p->state, ProgramState::kPlaying);
  EXPECT_EQ(p->program, "<unnamed>");
  EXPECT_EQ(ParseProgramStateReply("PAUSED")->state, ProgramState::kPaused);
  EXPECT_FALSE(ParseProgramStateReply("RUNNING x").ok());
}

TEST(DashboardEnums, NamesRoundTrip) {
  for (int v = -1; v <= 8; ++v) {
    const RobotMode m = *RobotModeFromInt(v);
    EXPECT_EQ(RobotModeFromName(RobotModeName(m)), m);
  }
  EXPECT_EQ(RobotModeFromInt(9), std::nullopt);
  for (int v = 1; v <= 13; ++v) {
    const SafetyMode m = *SafetyModeFromInt(v);
    EXPECT_EQ(SafetyModeFromName(SafetyModeName(m)), m);
  }
  EXPECT_EQ(SafetyModeFromInt(0), std::nullopt);
  EXPECT_STREQ(SafetyModeName(static_cast<SafetyMode>(17)), "UNKNOWN");
  EXPECT_STREQ(RobotModeName(RobotMode::kRunning), "RUNNING");
  EXPECT_STREQ(SafetyModeName(SafetyMode::kProtectiveStop), "PROTECTIVE_STOP");
}

}  // namespace
}  // namespace cornerpose::ur
