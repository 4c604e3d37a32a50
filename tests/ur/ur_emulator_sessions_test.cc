// The UR emulator's byte-level sessions: how primary text is split into
// scripts and control words, dashboard replies that change the controller,
// and the RTDE v1 path.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "absl/strings/str_split.h"
#include "robot_client/ur/rtde.h"
#include "tests/support/ur_emulator/sessions.h"

namespace cornerpose::ur_emulator {
namespace {

using ::testing::ElementsAre;

std::vector<PrimaryScriptAssembler::Item> Feed(const std::string& text) {
  PrimaryScriptAssembler assembler;
  std::vector<PrimaryScriptAssembler::Item> items;
  for (absl::string_view line : absl::StrSplit(text, '\n')) {
    if (auto item = assembler.AddLine(line)) items.push_back(*item);
  }
  return items;
}

TEST(PrimaryScriptAssembler, SplitsProgramsControlWordsAndStatements) {
  const auto items = Feed(
      "power on\n"
      "def a():\n"
      "  sync()\n"
      "  # end\n"
      "end\n"
      "\n"
      "set_tool_digital_out(0, True)\n"
      "  set unlock protective stop  \n"
      "sec b():\r\n"
      "  sync()\r\n"
      "end\r\n");
  ASSERT_EQ(items.size(), 5u);
  EXPECT_TRUE(items[0].control_word);
  EXPECT_EQ(items[0].text, "power on");
  EXPECT_FALSE(items[1].control_word);
  EXPECT_EQ(items[1].text, "def a():\n  sync()\n  # end\nend\n");
  EXPECT_EQ(items[2].text, "set_tool_digital_out(0, True)\n");
  EXPECT_TRUE(items[3].control_word);
  EXPECT_EQ(items[3].text, "set unlock protective stop");
  EXPECT_EQ(items[4].text, "sec b():\n  sync()\nend\n");
}

TEST(PrimaryScriptAssembler, ProgramWithoutEndWaitsForMore) {
  EXPECT_TRUE(Feed("def a():\n  sync()\n").empty());
}

TEST(DashboardReply, StopEndsTheRunningProgram) {
  UrEmulatorOptions options;
  options.start_powered_off = false;
  options.time_scale = 20.0;
  Controller controller(options);
  controller.SubmitScript("def wait():\n  sleep(1000)\nend\n");
  ASSERT_TRUE(controller.WaitFor([](const RobotSnapshot& s) { return s.program_running; },
                                 absl::Seconds(20)));
  bool close = true;
  EXPECT_EQ(DashboardReply(controller, "programState", &close), "PLAYING wait");
  EXPECT_FALSE(close);
  EXPECT_EQ(DashboardReply(controller, "stop\r", &close), "Stopped");
  ASSERT_TRUE(controller.WaitFor([](const RobotSnapshot& s) { return s.programs_finished == 1; },
                                 absl::Seconds(20)));
  EXPECT_EQ(controller.Programs()[0].outcome, ProgramOutcome::kAborted);
  EXPECT_EQ(DashboardReply(controller, "programState", &close), "STOPPED wait");
  EXPECT_EQ(DashboardReply(controller, "load x.urp", &close), "File not found: x.urp");
  EXPECT_EQ(DashboardReply(controller, "quit", &close), "Disconnected");
  EXPECT_TRUE(close);
}

TEST(RtdeSession, Version1HasNoFrequencyAndNoRecipeIdInPackages) {
  UrEmulatorOptions options;
  RtdeSession session(options);
  auto handle = [&](const std::string& frame) {
    auto parsed = ur::ParseRtdeFrame(frame);
    EXPECT_TRUE(parsed.ok());
    return session.Handle(*parsed);
  };
  EXPECT_EQ(handle(ur::EncodeRequestProtocolVersion(1)),
            ur::EncodeAccepted(ur::RtdeMessageType::kRequestProtocolVersion, true));
  EXPECT_EQ(handle(ur::EncodeRequestProtocolVersion(3)),
            ur::EncodeAccepted(ur::RtdeMessageType::kRequestProtocolVersion, false));
  // v1 setup: names only.
  const std::string reply =
      handle(ur::EncodeRtdeFrame(ur::RtdeMessageType::kSetupOutputs, "robot_mode,speed_scaling"));
  auto setup = ur::ParseSetupReply(ur::ParseRtdeFrame(reply)->payload);
  ASSERT_TRUE(setup.ok());
  EXPECT_EQ(setup->recipe_id, 1);
  EXPECT_THAT(setup->types, ElementsAre("INT32", "DOUBLE"));
  EXPECT_FALSE(session.streaming());
  handle(ur::EncodeStart());
  EXPECT_TRUE(session.streaming());
  EXPECT_DOUBLE_EQ(session.period_s(), 1.0 / 125.0);
  RobotSnapshot snapshot;
  snapshot.robot_mode = kRobotModeRunning;
  const std::string package = session.DataPackage(snapshot);
  ASSERT_EQ(package.size(), 3u + 4u + 8u);  // header, INT32, DOUBLE
  EXPECT_EQ(package[6], 7);                 // robot mode, big-endian
  handle(ur::EncodePause());
  EXPECT_FALSE(session.streaming());
}

TEST(RtdeSession, StartWithoutRecipeIsRefusedAndFrequencyIsCapped) {
  UrEmulatorOptions options;
  RtdeSession session(options);
  auto handle = [&](const std::string& frame) {
    return session.Handle(*ur::ParseRtdeFrame(frame));
  };
  handle(ur::EncodeRequestProtocolVersion(2));
  EXPECT_EQ(handle(ur::EncodeStart()), ur::EncodeAccepted(ur::RtdeMessageType::kStart, false));
  handle(ur::EncodeSetupOutputs({5000.0, {"timestamp"}}));
  EXPECT_DOUBLE_EQ(session.period_s(), 1.0 / 500.0);
}

}  // namespace
}  // namespace cornerpose::ur_emulator
