// The UR emulator's simulated controller without sockets: mode changes,
// program execution and recording, protective stops.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "absl/strings/str_cat.h"
#include "robot_client/ur/kinematics.h"
#include "tests/support/ur_emulator/controller.h"

namespace cornerpose::ur_emulator {
namespace {

using ::testing::HasSubstr;

constexpr absl::Duration kTimeout = absl::Seconds(20);

UrEmulatorOptions FastOptions() {
  UrEmulatorOptions options;
  options.time_scale = 20.0;
  options.start_powered_off = false;
  return options;
}

// The home TCP pose shifted by (dx, dy, dz) in the base frame.
ur::UrPose Shifted(const UrEmulatorOptions& options, double dx, double dy, double dz) {
  ur::UrPose p = ur::ToUrPose(ur::ForwardKinematics(options.model, options.initial_joints));
  p.position += Eigen::Vector3d(dx, dy, dz);
  return p;
}

bool WaitFinished(const Controller& c, size_t n) {
  return c.WaitFor([n](const RobotSnapshot& s) { return s.programs_finished >= n; }, kTimeout);
}

TEST(UrEmulatorController, PowerOnAndBrakeReleaseReachRunning) {
  UrEmulatorOptions options = FastOptions();
  options.start_powered_off = true;
  Controller c(options);
  EXPECT_EQ(c.Snapshot().robot_mode, kRobotModePowerOff);
  EXPECT_FALSE(c.BrakeRelease());  // not powered
  EXPECT_TRUE(c.PowerOn());
  ASSERT_TRUE(
      c.WaitFor([](const RobotSnapshot& s) { return s.robot_mode == kRobotModeIdle; }, kTimeout));
  EXPECT_TRUE(c.BrakeRelease());
  ASSERT_TRUE(c.WaitFor([](const RobotSnapshot& s) { return s.robot_mode == kRobotModeRunning; },
                        kTimeout));
}

TEST(UrEmulatorController, ScriptIsRejectedWhilePoweredOff) {
  UrEmulatorOptions options = FastOptions();
  options.start_powered_off = true;
  Controller c(options);
  c.SubmitScript("def p():\n  set_tool_digital_out(0, True)\nend\n");
  ASSERT_TRUE(WaitFinished(c, 1));
  const auto programs = c.Programs();
  ASSERT_EQ(programs.size(), 1u);
  EXPECT_EQ(programs[0].outcome, ProgramOutcome::kRejected);
  EXPECT_TRUE(programs[0].steps.empty());
  EXPECT_EQ(c.Snapshot().tool_outputs, 0u);
}

TEST(UrEmulatorController, ExecutesMovesAndOutputsAndRecordsThem) {
  const UrEmulatorOptions options = FastOptions();
  Controller c(options);
  const ur::UrPose above = Shifted(options, 0.1, 0.05, -0.05);
  const ur::UrPose grasp = Shifted(options, 0.1, 0.05, -0.15);
  const std::string script = absl::StrCat(
      "def pick():\n", "  set_tcp(p[0, 0, 0.1, 0, 0, 0])\n", "  movej(",
      ur::FormatPoseLiteral(above), ", a=1.4, v=1.05)\n", "  movel(", ur::FormatPoseLiteral(grasp),
      ", a=1.2, v=0.25)\n", "  set_tool_digital_out(0, True)\n", "  sleep(0.2)\n", "  movel(",
      ur::FormatPoseLiteral(above), ")\n", "  set_tool_digital_out(0, False)\n",
      "  textmsg(\"done\")\n", "end\n");
  uint64_t cursor = c.EventCursor();
  c.SubmitScript(script);
  ASSERT_TRUE(WaitFinished(c, 1));
  const auto programs = c.Programs();
  ASSERT_EQ(programs.size(), 1u);
  const ExecutedProgram& p = programs[0];
  EXPECT_EQ(p.name, "pick");
  EXPECT_EQ(p.outcome, ProgramOutcome::kCompleted) << p.error_text;
  ASSERT_EQ(p.steps.size(), 8u);

  // Note: set_tcp comes first, so every target is a TCP pose with the offset.
  const Eigen::Isometry3d tcp = ur::FromUrPose(ur::UrPose{Eigen::Vector3d(0, 0, 0.1), {}});
  for (const ExecutedStep& step : p.steps) {
    SCOPED_TRACE(step.kind);
    EXPECT_TRUE(step.completed);
    const Eigen::Isometry3d fk = ur::ForwardKinematics(options.model, step.joints) * tcp;
    EXPECT_LT((fk.translation() - step.tcp.position).norm(), 1e-9);
    EXPECT_LT(ur::RotationAngleBetween(Eigen::Quaterniond(fk.linear()),
                                       ur::QuaternionFromRotationVector(step.tcp.rotation)),
              1e-9);
    EXPECT_LE(step.start_time_s, step.end_time_s);
  }
  const ur::UrPose* targets[] = {&above, &grasp, &above};
  const int move_steps[] = {1, 2, 5};
  for (int i = 0; i < 3; ++i) {
    const ExecutedStep& step = p.steps[move_steps[i]];
    ASSERT_TRUE(step.target);
    EXPECT_LT((step.tcp.position - targets[i]->position).norm(), 1e-4) << step.kind;
    EXPECT_LT((step.target->position - targets[i]->position).norm(), 1e-6) << step.kind;
    EXPECT_LT(ur::RotationAngleBetween(ur::QuaternionFromRotationVector(step.tcp.rotation),
                                       ur::QuaternionFromRotationVector(targets[i]->rotation)),
              1e-4);
  }
  // The tool output is on exactly from the first set_* to the second.
  const uint32_t expected_tool[] = {0, 0, 0, 1, 1, 1, 0, 0};
  for (size_t i = 0; i < p.steps.size(); ++i) {
    EXPECT_EQ(p.steps[i].tool_outputs, expected_tool[i]) << i << " " << p.steps[i].kind;
  }
  // sleep(0.2) lasts 0.2 s of simulated time (no upper bound: a busy
  // machine may run late).
  EXPECT_GE(p.steps[4].end_time_s - p.steps[4].start_time_s, 0.2 - 1e-9);

  // Events: STARTED, TEXT, STOPPED.
  std::vector<ControllerEvent> events;
  while (events.size() < 3) {
    auto more = c.NextEvents(&cursor, absl::Seconds(5));
    if (more.empty()) break;
    events.insert(events.end(), more.begin(), more.end());
  }
  ASSERT_EQ(events.size(), 3u);
  EXPECT_EQ(events[0].kind, ControllerEvent::Kind::kProgramStarted);
  EXPECT_EQ(events[0].text, "pick");
  EXPECT_EQ(events[1].kind, ControllerEvent::Kind::kText);
  EXPECT_EQ(events[1].text, "done");
  EXPECT_EQ(events[2].kind, ControllerEvent::Kind::kProgramStopped);
  EXPECT_EQ(events[2].text, "pick");
}

TEST(UrEmulatorController, MovelPassesThroughAStraightLine) {
  const UrEmulatorOptions options = FastOptions();
  Controller c(options);
  const ur::UrPose start = Shifted(options, 0, 0, 0);
  const ur::UrPose end = Shifted(options, 0.15, -0.1, -0.1);
  c.SubmitScript(
      absl::StrCat("def line():\n  movel(", ur::FormatPoseLiteral(end), ", a=2, v=0.5)\nend\n"));
  // Sample the TCP while it moves: every sample lies on the segment.
  double worst = 0.0;
  int samples = 0;
  c.WaitFor(
      [&](const RobotSnapshot& s) {
        const Eigen::Vector3d d = end.position - start.position;
        const Eigen::Vector3d v = s.tcp.position - start.position;
        const double along = std::clamp(v.dot(d) / d.squaredNorm(), 0.0, 1.0);
        worst = std::max(worst, (v - along * d).norm());
        ++samples;
        return s.programs_finished >= 1;
      },
      kTimeout);
  ASSERT_TRUE(WaitFinished(c, 1));
  EXPECT_EQ(c.Programs()[0].outcome, ProgramOutcome::kCompleted);
  EXPECT_GT(samples, 2);
  EXPECT_LT(worst, 1e-6);
}

TEST(UrEmulatorController, UnreachableTargetIsARuntimeException) {
  const UrEmulatorOptions options = FastOptions();
  Controller c(options);
  uint64_t cursor = c.EventCursor();
  c.SubmitScript(
      "def far():\n  set_tool_digital_out(1, True)\n  movej(p[3, 0, 0.3, 3.14, 0, 0])\n"
      "  set_tool_digital_out(1, False)\nend\n");
  ASSERT_TRUE(WaitFinished(c, 1));
  const ExecutedProgram p = c.Programs()[0];
  EXPECT_EQ(p.outcome, ProgramOutcome::kRuntimeException);
  EXPECT_THAT(p.error_text, HasSubstr("inverse_kinematics"));
  EXPECT_EQ(p.error_line, 3);
  EXPECT_EQ(p.error_column, 3);
  EXPECT_EQ(p.steps.size(), 1u);
  EXPECT_EQ(c.Snapshot().tool_outputs, 2u);  // the last set_ never ran
  bool saw_exception = false;
  for (const auto& e : c.NextEvents(&cursor, absl::Seconds(5))) {
    saw_exception |= e.kind == ControllerEvent::Kind::kRuntimeException;
  }
  EXPECT_TRUE(saw_exception);
}

TEST(UrEmulatorController, BadScriptExecutesNothing) {
  const UrEmulatorOptions options = FastOptions();
  Controller c(options);
  c.SubmitScript("def bad():\n  set_tool_digital_out(0, True)\n  foo()\nend\n");
  ASSERT_TRUE(WaitFinished(c, 1));
  const ExecutedProgram p = c.Programs()[0];
  EXPECT_EQ(p.outcome, ProgramOutcome::kRuntimeException);
  EXPECT_EQ(p.error_text, "compile_error_name_not_found:foo:");
  EXPECT_EQ(p.error_line, 3);
  EXPECT_TRUE(p.steps.empty());
  EXPECT_EQ(c.Snapshot().tool_outputs, 0u);
}

TEST(UrEmulatorController, NewProgramAbortsTheRunningOne) {
  const UrEmulatorOptions options = FastOptions();
  Controller c(options);
  c.SubmitScript("def slow():\n  sleep(1000)\nend\n");
  ASSERT_TRUE(c.WaitFor([](const RobotSnapshot& s) { return s.program_running; }, kTimeout));
  c.SubmitScript("def fast():\n  set_standard_digital_out(2, True)\nend\n");
  ASSERT_TRUE(WaitFinished(c, 2));
  const auto programs = c.Programs();
  ASSERT_EQ(programs.size(), 2u);
  EXPECT_EQ(programs[0].outcome, ProgramOutcome::kAborted);
  EXPECT_EQ(programs[1].outcome, ProgramOutcome::kCompleted);
  EXPECT_EQ(c.Snapshot().standard_outputs, 4u);
}

TEST(UrEmulatorController, ProtectiveStopHaltsMotionAndUnlockWaitsForTheDelay) {
  UrEmulatorOptions options = FastOptions();
  options.protective_stop_unlock_delay_s = 60.0;  // 3 s of wall time
  Controller c(options);
  const ur::UrPose far = Shifted(options, 0.2, 0.2, -0.2);
  c.SubmitScript(
      absl::StrCat("def long():\n  movel(", ur::FormatPoseLiteral(far), ", a=0.1, v=0.02)\nend\n"));
  ASSERT_TRUE(c.WaitFor(
      [](const RobotSnapshot& s) {
        return s.program_running && (s.joint_speeds[0] != 0 || s.joint_speeds[1] != 0);
      },
      kTimeout));
  c.TriggerProtectiveStop();
  ASSERT_TRUE(WaitFinished(c, 1));
  const RobotSnapshot stopped = c.Snapshot();
  EXPECT_EQ(stopped.safety_mode, kSafetyModeProtectiveStop);
  EXPECT_EQ(stopped.robot_mode, kRobotModeRunning);
  const ExecutedProgram p = c.Programs()[0];
  EXPECT_EQ(p.outcome, ProgramOutcome::kProtectiveStop);
  ASSERT_EQ(p.steps.size(), 1u);
  EXPECT_FALSE(p.steps[0].completed);
  EXPECT_GT((p.steps[0].tcp.position - far.position).norm(), 0.01);
  // No motion after the stop.
  const double t = c.SimTime();
  ASSERT_TRUE(c.WaitFor([t](const RobotSnapshot& s) { return s.time_s > t + 1.0; }, kTimeout));
  EXPECT_EQ(c.Snapshot().joints, stopped.joints);
  // A script is not started while stopped.
  c.SubmitScript("def again():\n  sync()\nend\n");
  ASSERT_TRUE(WaitFinished(c, 2));
  EXPECT_EQ(c.Programs()[1].outcome, ProgramOutcome::kRejected);

  EXPECT_FALSE(c.UnlockProtectiveStop());
  ASSERT_TRUE(c.WaitFor([&](const RobotSnapshot& s) { return s.time_s > t + 61.0; }, kTimeout));
  EXPECT_TRUE(c.UnlockProtectiveStop());
  EXPECT_EQ(c.Snapshot().safety_mode, kSafetyModeNormal);
}

TEST(UrEmulatorController, ProtectiveStopFromTheScript) {
  Controller c(FastOptions());
  c.SubmitScript("def ps():\n  protective_stop()\n  set_tool_digital_out(0, True)\nend\n");
  ASSERT_TRUE(WaitFinished(c, 1));
  EXPECT_EQ(c.Programs()[0].outcome, ProgramOutcome::kProtectiveStop);
  EXPECT_EQ(c.Snapshot().safety_mode, kSafetyModeProtectiveStop);
  EXPECT_EQ(c.Snapshot().tool_outputs, 0u);
}

}  // namespace
}  // namespace cornerpose::ur_emulator
