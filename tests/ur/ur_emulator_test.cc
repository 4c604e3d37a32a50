// The UR controller emulator over real loopback TCP: the dashboard bring-up,
// scripts on the primary port with their KEY / TEXT / RUNTIME_EXCEPTION
// feedback, protective stops, dropped connections and RTDE, decoded with the
// daemon's own wire-format code (robot_client/ur).
#include "tests/support/ur_emulator/ur_emulator.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <variant>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "robot_client/ur/kinematics.h"
#include "robot_client/ur/primary.h"
#include "robot_client/ur/rtde.h"
#include "robot_client/ur/tcp.h"

namespace cornerpose::ur_emulator {
namespace {

using ::testing::HasSubstr;
using ::testing::StartsWith;

constexpr absl::Duration kTimeout = absl::Seconds(20);

UrEmulatorOptions FastOptions(bool powered) {
  UrEmulatorOptions options;
  options.time_scale = 20.0;
  options.start_powered_off = !powered;
  return options;
}

std::unique_ptr<UrEmulator> StartEmulator(const UrEmulatorOptions& options) {
  auto emulator = UrEmulator::Start(options);
  EXPECT_TRUE(emulator.ok()) << emulator.status();
  return emulator.ok() ? std::move(*emulator) : nullptr;
}

ur::TcpConnection ConnectTo(int port) {
  auto connection = ur::TcpConnection::Connect("127.0.0.1", port, absl::Seconds(5));
  EXPECT_TRUE(connection.ok()) << connection.status();
  return connection.ok() ? std::move(*connection) : ur::TcpConnection();
}

ur::UrPose Shifted(const UrEmulatorOptions& options, double dx, double dy, double dz) {
  ur::UrPose p = ur::ToUrPose(ur::ForwardKinematics(options.model, options.initial_joints));
  p.position += Eigen::Vector3d(dx, dy, dz);
  return p;
}

// ---- Dashboard ----

class Dashboard {
 public:
  explicit Dashboard(int port) : connection_(ConnectTo(port)) {}
  std::string Banner() { return Line(); }
  std::string Send(const std::string& command) {
    EXPECT_TRUE(connection_.WriteAll(command + "\n").ok());
    return Line();
  }
  ur::TcpConnection& connection() { return connection_; }

 private:
  std::string Line() {
    auto line = connection_.ReadLine(kTimeout);
    EXPECT_TRUE(line.ok()) << line.status();
    return line.ok() ? *line : "";
  }
  ur::TcpConnection connection_;
};

TEST(UrEmulator, DashboardBringUpSequence) {
  auto emulator = StartEmulator(FastOptions(/*powered=*/false));
  ASSERT_TRUE(emulator);
  Dashboard dashboard(emulator->dashboard_port());
  EXPECT_EQ(dashboard.Banner(), "Connected: Universal Robots Dashboard Server");
  EXPECT_EQ(dashboard.Send("robotmode"), "Robotmode: POWER_OFF");
  EXPECT_EQ(dashboard.Send("power on"), "Powering on");
  ASSERT_TRUE(emulator->WaitFor(
      [](const RobotSnapshot& s) { return s.robot_mode == kRobotModeIdle; }, kTimeout));
  EXPECT_EQ(dashboard.Send("robotmode"), "Robotmode: IDLE");
  EXPECT_EQ(dashboard.Send("brake release"), "Brake releasing");
  ASSERT_TRUE(emulator->WaitFor(
      [](const RobotSnapshot& s) { return s.robot_mode == kRobotModeRunning; }, kTimeout));
  EXPECT_EQ(dashboard.Send("robotmode"), "Robotmode: RUNNING");
  EXPECT_EQ(dashboard.Send("safetymode"), "Safetymode: NORMAL");
  EXPECT_EQ(dashboard.Send("safetystatus"), "Safetystatus: NORMAL");
  EXPECT_EQ(dashboard.Send("running"), "Program running: false");
  EXPECT_EQ(dashboard.Send("programState"), "STOPPED <unnamed>");
  EXPECT_EQ(dashboard.Send("is in remote control"), "true");
  EXPECT_THAT(dashboard.Send("PolyscopeVersion"), StartsWith("URSoftware 5.11."));
  EXPECT_EQ(dashboard.Send("play"), "Failed to execute: play");
  EXPECT_EQ(dashboard.Send("stop"), "Failed to execute: stop");  // nothing runs
  EXPECT_EQ(dashboard.Send("close safety popup"), "closing safety popup");
  EXPECT_EQ(dashboard.Send("unlock protective stop"), "Protective stop releasing");
  EXPECT_EQ(dashboard.Send("make coffee"), "could not understand: 'make coffee'");
  EXPECT_EQ(dashboard.Send("power off"), "Powering off");
  EXPECT_EQ(dashboard.Send("robotmode"), "Robotmode: POWER_OFF");
  EXPECT_EQ(dashboard.Send("quit"), "Disconnected");
  EXPECT_FALSE(dashboard.connection().ReadLine(kTimeout).ok());  // closed by the server
}

// ---- Primary ----

class Primary {
 public:
  explicit Primary(int port) : connection_(ConnectTo(port)) {}
  void Send(const std::string& text) { ASSERT_TRUE(connection_.WriteAll(text).ok()); }

  // Reads packages until `done` returns true for one; false on timeout or
  // a closed connection. Every package read is kept in packages().
  bool ReadUntil(const std::function<bool(const ur::PrimaryPackage&)>& done,
                 absl::Duration timeout = kTimeout) {
    const absl::Time deadline = absl::Now() + timeout;
    while (true) {
      auto next = framer_.Next();
      if (!next.ok()) return false;
      if (next->has_value()) {
        auto package = ur::ParsePrimaryPackage(**next);
        EXPECT_TRUE(package.ok()) << package.status();
        if (!package.ok()) return false;
        packages_.push_back(*package);
        if (done(*package)) return true;
        continue;
      }
      const absl::Duration left = deadline - absl::Now();
      if (left <= absl::ZeroDuration()) return false;
      auto bytes = connection_.Read(65536, left);
      if (!bytes.ok()) return false;
      framer_.Append(*bytes);
    }
  }
  const std::vector<ur::PrimaryPackage>& packages() const { return packages_; }
  ur::TcpConnection& connection() { return connection_; }

 private:
  ur::TcpConnection connection_;
  ur::PrimaryFramer framer_;
  std::vector<ur::PrimaryPackage> packages_;
};

std::function<bool(const ur::PrimaryPackage&)> IsKey(const std::string& title,
                                                     const std::string& text) {
  return [=](const ur::PrimaryPackage& p) {
    const auto* key = std::get_if<ur::KeyMessage>(&p);
    return key != nullptr && key->title == title && key->text == text;
  };
}

TEST(UrEmulator, PrimarySendsVersionThenState) {
  auto emulator = StartEmulator(FastOptions(/*powered=*/true));
  ASSERT_TRUE(emulator);
  Primary primary(emulator->primary_port());
  ASSERT_TRUE(primary.ReadUntil(
      [](const ur::PrimaryPackage& p) { return std::holds_alternative<ur::RobotState>(p); }));
  const auto* version = std::get_if<ur::VersionMessage>(&primary.packages()[0]);
  ASSERT_NE(version, nullptr);
  EXPECT_EQ(version->project_name, "URControl");
  EXPECT_EQ(version->major, 5);
  const auto& state = std::get<ur::RobotState>(primary.packages().back());
  ASSERT_TRUE(state.robot_mode && state.joints && state.cartesian && state.masterboard);
  EXPECT_EQ(state.robot_mode->robot_mode, kRobotModeRunning);
  EXPECT_FALSE(state.robot_mode->program_running);
  EXPECT_EQ(ur::ActualJoints(*state.joints), emulator->options().initial_joints);
  const Eigen::Isometry3d fk =
      ur::ForwardKinematics(emulator->options().model, ur::ActualJoints(*state.joints));
  EXPECT_LT((fk.translation() - state.cartesian->tcp_pose.position).norm(), 1e-9);
}

TEST(UrEmulator, ScriptRunsWithFeedbackAndIsRecorded) {
  const UrEmulatorOptions options = FastOptions(/*powered=*/true);
  auto emulator = StartEmulator(options);
  ASSERT_TRUE(emulator);
  Primary primary(emulator->primary_port());
  const ur::UrPose above = Shifted(options, 0.1, -0.1, -0.05);
  const ur::UrPose grasp = Shifted(options, 0.1, -0.1, -0.2);
  const ur::UrPose place = Shifted(options, -0.15, -0.05, 0.0);
  const std::string script = absl::StrCat(
      "def job_7():\n", "  set_tcp(p[0, 0, 0.12, 0, 0, 0])\n", "  movej(",
      ur::FormatPoseLiteral(above), ", a=1.0, v=0.8)\n", "  movel(", ur::FormatPoseLiteral(grasp),
      ", a=0.5, v=0.05)\n", "  set_tool_digital_out(0, True)\n", "  sleep(0.3)\n", "  movel(",
      ur::FormatPoseLiteral(above), ", a=0.5, v=0.1)\n", "  movej(", ur::FormatPoseLiteral(place),
      ", a=1.0, v=0.8)\n", "  set_tool_digital_out(0, False)\n", "  textmsg(\"placed \", 7)\n",
      "end\n");
  primary.Send(script);
  ASSERT_TRUE(primary.ReadUntil(IsKey("PROGRAM_XXX_STOPPED", "job_7")));

  // Feedback in order: STARTED, TEXT, STOPPED; state in between says running.
  std::vector<std::string> feedback;
  bool saw_running_state = false;
  for (const auto& p : primary.packages()) {
    if (const auto* key = std::get_if<ur::KeyMessage>(&p)) feedback.push_back(key->title);
    if (const auto* text = std::get_if<ur::TextMessage>(&p)) feedback.push_back(text->text);
    if (const auto* state = std::get_if<ur::RobotState>(&p)) {
      saw_running_state |= state->robot_mode && state->robot_mode->program_running;
    }
    EXPECT_FALSE(std::holds_alternative<ur::RuntimeExceptionMessage>(p));
  }
  EXPECT_THAT(feedback,
              ::testing::ElementsAre("PROGRAM_XXX_STARTED", "placed 7", "PROGRAM_XXX_STOPPED"));
  EXPECT_TRUE(saw_running_state);

  const auto programs = emulator->Programs();
  ASSERT_EQ(programs.size(), 1u);
  const ExecutedProgram& p = programs[0];
  EXPECT_EQ(p.text, script);
  EXPECT_EQ(p.outcome, ProgramOutcome::kCompleted);
  ASSERT_EQ(p.steps.size(), 9u);
  const Eigen::Isometry3d tcp = ur::FromUrPose(ur::UrPose{Eigen::Vector3d(0, 0, 0.12), {}});
  for (const ExecutedStep& step : p.steps) {
    SCOPED_TRACE(step.kind);
    const Eigen::Isometry3d fk = ur::ForwardKinematics(options.model, step.joints) * tcp;
    EXPECT_LT((fk.translation() - step.tcp.position).norm(), 1e-9);
    EXPECT_LT(ur::RotationAngleBetween(Eigen::Quaterniond(fk.linear()),
                                       ur::QuaternionFromRotationVector(step.tcp.rotation)),
              1e-9);
    if (step.target) {
      EXPECT_LT((step.tcp.position - step.target->position).norm(), 1e-4);
      EXPECT_LT(ur::RotationAngleBetween(ur::QuaternionFromRotationVector(step.tcp.rotation),
                                         ur::QuaternionFromRotationVector(step.target->rotation)),
                1e-4);
    }
  }
  const std::pair<int, const ur::UrPose*> moves[] = {
      {1, &above}, {2, &grasp}, {5, &above}, {6, &place}};
  for (const auto& [index, target] : moves) {
    EXPECT_LT((p.steps[index].tcp.position - target->position).norm(), 1e-4) << index;
  }
  // Suction on exactly between the two set_tool_digital_out calls.
  const uint32_t expected_tool[] = {0, 0, 0, 1, 1, 1, 1, 0, 0};
  for (size_t i = 0; i < p.steps.size(); ++i) {
    EXPECT_EQ(p.steps[i].tool_outputs, expected_tool[i]) << i << " " << p.steps[i].kind;
  }
  EXPECT_EQ(emulator->Snapshot().tool_outputs, 0u);
}

TEST(UrEmulator, BadScriptGivesRuntimeExceptionAndExecutesNothing) {
  auto emulator = StartEmulator(FastOptions(/*powered=*/true));
  ASSERT_TRUE(emulator);
  Primary primary(emulator->primary_port());
  primary.Send("def bad():\n  set_tool_digital_out(0, True)\n  movej([0,0,0,0,0,0]\nend\n");
  ASSERT_TRUE(primary.ReadUntil([](const ur::PrimaryPackage& p) {
    return std::holds_alternative<ur::RuntimeExceptionMessage>(p);
  }));
  const auto& exception = std::get<ur::RuntimeExceptionMessage>(primary.packages().back());
  EXPECT_EQ(exception.line, 3);
  EXPECT_EQ(exception.column, 22);
  EXPECT_THAT(exception.text, HasSubstr("syntax_error_on_line:3"));
  for (const auto& p : primary.packages()) {
    EXPECT_FALSE(std::holds_alternative<ur::KeyMessage>(p));
  }
  const auto programs = emulator->Programs();
  ASSERT_EQ(programs.size(), 1u);
  EXPECT_EQ(programs[0].outcome, ProgramOutcome::kRuntimeException);
  EXPECT_TRUE(programs[0].steps.empty());
  const RobotSnapshot s = emulator->Snapshot();
  EXPECT_EQ(s.tool_outputs, 0u);
  EXPECT_EQ(s.joints, emulator->options().initial_joints);

  // Unknown function: the controller's own error text.
  primary.Send("def unknown():\n  calldoesntexist()\nend\n");
  ASSERT_TRUE(primary.ReadUntil([](const ur::PrimaryPackage& p) {
    const auto* e = std::get_if<ur::RuntimeExceptionMessage>(&p);
    return e != nullptr && e->text == "compile_error_name_not_found:calldoesntexist:";
  }));
  const auto& unknown = std::get<ur::RuntimeExceptionMessage>(primary.packages().back());
  EXPECT_EQ(unknown.line, 2);
  EXPECT_EQ(unknown.column, 3);
}

TEST(UrEmulator, ProtectiveStopHaltsMotionAndUnlockWaitsForTheDelay) {
  UrEmulatorOptions options = FastOptions(/*powered=*/true);
  options.protective_stop_unlock_delay_s = 60.0;  // 3 s of wall time
  auto emulator = StartEmulator(options);
  ASSERT_TRUE(emulator);
  Primary primary(emulator->primary_port());
  Dashboard dashboard(emulator->dashboard_port());
  dashboard.Banner();
  const ur::UrPose far = Shifted(options, 0.2, 0.1, -0.2);
  primary.Send(
      absl::StrCat("def slow():\n  movel(", ur::FormatPoseLiteral(far), ", a=0.1, v=0.02)\nend\n"));
  ASSERT_TRUE(primary.ReadUntil(IsKey("PROGRAM_XXX_STARTED", "slow")));
  ASSERT_TRUE(emulator->WaitFor(
      [&](const RobotSnapshot& s) { return s.joints != options.initial_joints; }, kTimeout));
  EXPECT_EQ(dashboard.Send("running"), "Program running: true");
  EXPECT_EQ(dashboard.Send("programState"), "PLAYING slow");
  emulator->TriggerProtectiveStop();
  ASSERT_TRUE(primary.ReadUntil(IsKey("PROGRAM_XXX_STOPPED", "slow")));
  bool saw_safety_message = false;
  for (const auto& p : primary.packages()) {
    if (const auto* m = std::get_if<ur::SafetyModeMessage>(&p)) {
      saw_safety_message |= m->safety_mode == kSafetyModeProtectiveStop;
    }
  }
  EXPECT_TRUE(saw_safety_message);
  ASSERT_TRUE(primary.ReadUntil([](const ur::PrimaryPackage& p) {
    const auto* state = std::get_if<ur::RobotState>(&p);
    return state && state->robot_mode && state->robot_mode->protective_stopped;
  }));
  EXPECT_EQ(dashboard.Send("safetystatus"), "Safetystatus: PROTECTIVE_STOP");
  EXPECT_EQ(dashboard.Send("robotmode"), "Robotmode: RUNNING");

  const auto programs = emulator->Programs();
  ASSERT_EQ(programs.size(), 1u);
  EXPECT_EQ(programs[0].outcome, ProgramOutcome::kProtectiveStop);
  ASSERT_EQ(programs[0].steps.size(), 1u);
  EXPECT_FALSE(programs[0].steps[0].completed);
  const ur::Joints halted = emulator->Snapshot().joints;
  EXPECT_EQ(halted, programs[0].steps[0].joints);
  EXPECT_GT((programs[0].steps[0].tcp.position - far.position).norm(), 0.01);

  EXPECT_THAT(dashboard.Send("unlock protective stop"), HasSubstr("Cannot unlock"));
  const double stop_time = emulator->Snapshot().time_s;
  ASSERT_TRUE(emulator->WaitFor([&](const RobotSnapshot& s) { return s.time_s > stop_time + 61.0; },
                                kTimeout));
  EXPECT_EQ(emulator->Snapshot().joints, halted);  // nothing moved while stopped
  EXPECT_EQ(dashboard.Send("unlock protective stop"), "Protective stop releasing");
  EXPECT_EQ(dashboard.Send("safetymode"), "Safetymode: NORMAL");
}

TEST(UrEmulator, ProtectiveStopFromScriptAndUnlockOverPrimary) {
  UrEmulatorOptions options = FastOptions(/*powered=*/true);
  options.protective_stop_unlock_delay_s = 1.0;
  auto emulator = StartEmulator(options);
  ASSERT_TRUE(emulator);
  Primary primary(emulator->primary_port());
  primary.Send("def ps():\n  protective_stop()\nend\n");
  ASSERT_TRUE(primary.ReadUntil(IsKey("PROGRAM_XXX_STOPPED", "ps")));
  EXPECT_EQ(emulator->Snapshot().safety_mode, kSafetyModeProtectiveStop);
  const double stop_time = emulator->Snapshot().time_s;
  ASSERT_TRUE(emulator->WaitFor([&](const RobotSnapshot& s) { return s.time_s > stop_time + 2.0; },
                                kTimeout));
  primary.Send("set unlock protective stop\n");
  EXPECT_TRUE(emulator->WaitFor(
      [](const RobotSnapshot& s) { return s.safety_mode == kSafetyModeNormal; }, kTimeout));
  primary.Send("stop program\npower off\n");
  EXPECT_TRUE(emulator->WaitFor(
      [](const RobotSnapshot& s) { return s.robot_mode == kRobotModePowerOff; }, kTimeout));
}

TEST(UrEmulator, DropConnectionsClosesClientsAndReconnectWorks) {
  auto emulator = StartEmulator(FastOptions(/*powered=*/true));
  ASSERT_TRUE(emulator);
  Dashboard dashboard(emulator->dashboard_port());
  EXPECT_EQ(dashboard.Banner(), "Connected: Universal Robots Dashboard Server");
  Primary primary(emulator->primary_port());
  ASSERT_TRUE(primary.ReadUntil(
      [](const ur::PrimaryPackage& p) { return std::holds_alternative<ur::RobotState>(p); }));
  ur::TcpConnection rtde = ConnectTo(emulator->rtde_port());
  ASSERT_TRUE(rtde.WriteAll(ur::EncodeRequestProtocolVersion()).ok());
  ASSERT_TRUE(rtde.ReadExact(4, kTimeout).ok());

  emulator->DropConnections();
  // Each client sees its connection end (reads fail before the timeout).
  auto dashboard_read = dashboard.connection().ReadLine(kTimeout);
  EXPECT_FALSE(dashboard_read.ok());
  EXPECT_FALSE(absl::IsDeadlineExceeded(dashboard_read.status())) << dashboard_read.status();
  EXPECT_FALSE(primary.ReadUntil([](const ur::PrimaryPackage&) { return false; }));
  auto rtde_read = rtde.Read(16, kTimeout);
  EXPECT_FALSE(rtde_read.ok());
  EXPECT_FALSE(absl::IsDeadlineExceeded(rtde_read.status())) << rtde_read.status();

  Dashboard again(emulator->dashboard_port());
  EXPECT_EQ(again.Banner(), "Connected: Universal Robots Dashboard Server");
  EXPECT_EQ(again.Send("robotmode"), "Robotmode: RUNNING");
  Primary primary_again(emulator->primary_port());
  primary_again.Send("def after_drop():\n  sync()\nend\n");
  EXPECT_TRUE(primary_again.ReadUntil(IsKey("PROGRAM_XXX_STOPPED", "after_drop")));
}

// ---- RTDE ----

class Rtde {
 public:
  explicit Rtde(int port) : connection_(ConnectTo(port)) {}
  // Sends `request` and returns the next message of type `type`.
  ur::RtdeFrame Exchange(const std::string& request, ur::RtdeMessageType type) {
    EXPECT_TRUE(connection_.WriteAll(request).ok());
    return Next(type);
  }
  ur::RtdeFrame Next(ur::RtdeMessageType type) {
    const absl::Time deadline = absl::Now() + kTimeout;
    while (absl::Now() < deadline) {
      auto frame = framer_.Next();
      if (!frame.ok()) break;
      if (frame->has_value()) {
        if ((*frame)->type == static_cast<uint8_t>(type)) return **frame;
        continue;
      }
      auto bytes = connection_.Read(65536, deadline - absl::Now());
      if (!bytes.ok()) break;
      framer_.Append(*bytes);
    }
    ADD_FAILURE() << "no RTDE message of type " << static_cast<char>(type);
    return {};
  }

 private:
  ur::TcpConnection connection_;
  ur::RtdeFramer framer_;
};

TEST(UrEmulator, RtdeHandshakeAndDataPackages) {
  const UrEmulatorOptions options = FastOptions(/*powered=*/true);
  auto emulator = StartEmulator(options);
  ASSERT_TRUE(emulator);
  Rtde rtde(emulator->rtde_port());
  using T = ur::RtdeMessageType;

  auto accepted = ur::ParseAccepted(
      rtde.Exchange(ur::EncodeRequestProtocolVersion(2), T::kRequestProtocolVersion).payload);
  ASSERT_TRUE(accepted.ok());
  EXPECT_TRUE(*accepted);
  auto version = ur::ParseUrcontrolVersion(
      rtde.Exchange(ur::EncodeGetUrcontrolVersion(), T::kGetUrcontrolVersion).payload);
  ASSERT_TRUE(version.ok());
  EXPECT_EQ(version->major, 5u);

  // An unknown output: NOT_FOUND, recipe id 0.
  auto refused = ur::ParseSetupReply(
      rtde.Exchange(ur::EncodeSetupOutputs({125.0, {"actual_q", "no_such_variable"}}),
                    T::kSetupOutputs)
          .payload);
  ASSERT_TRUE(refused.ok());
  EXPECT_EQ(refused->recipe_id, 0);
  EXPECT_THAT(refused->types, ::testing::ElementsAre("VECTOR6D", "NOT_FOUND"));

  const std::vector<std::string> names = {
      "timestamp",         "actual_q",        "target_q",
      "actual_TCP_pose",   "target_TCP_pose", "actual_digital_output_bits",
      "robot_mode",        "safety_mode",     "safety_status_bits",
      "robot_status_bits", "runtime_state",   "speed_scaling"};
  auto reply = ur::ParseSetupReply(
      rtde.Exchange(ur::EncodeSetupOutputs({250.0, names}), T::kSetupOutputs).payload);
  ASSERT_TRUE(reply.ok());
  EXPECT_NE(reply->recipe_id, 0);
  auto types = ur::RecipeTypes(*reply, names);
  ASSERT_TRUE(types.ok()) << types.status();
  for (size_t i = 0; i < names.size(); ++i) {
    EXPECT_EQ((*types)[i], *ur::RtdeOutputType(names[i])) << names[i];
  }
  auto inputs = ur::ParseSetupReply(
      rtde.Exchange(ur::EncodeSetupInputs({"input_int_register_24"}), T::kSetupInputs).payload);
  ASSERT_TRUE(inputs.ok());
  EXPECT_NE(inputs->recipe_id, 0);
  EXPECT_THAT(inputs->types, ::testing::ElementsAre("INT32"));

  accepted = ur::ParseAccepted(rtde.Exchange(ur::EncodeStart(), T::kStart).payload);
  ASSERT_TRUE(accepted.ok());
  EXPECT_TRUE(*accepted);

  auto next_package = [&]() {
    auto package = ur::ParseDataPackage(rtde.Next(T::kDataPackage).payload, *types);
    EXPECT_TRUE(package.ok()) << package.status();
    return package.ok() ? *package : ur::RtdeDataPackage{};
  };
  const ur::RtdeDataPackage first = next_package();
  ASSERT_EQ(first.values.size(), names.size());
  EXPECT_EQ(first.recipe_id, reply->recipe_id);
  const auto q = std::get<std::array<double, 6>>(first.values[1]);
  for (int i = 0; i < 6; ++i) EXPECT_EQ(q[i], options.initial_joints[i]);
  const auto pose = std::get<std::array<double, 6>>(first.values[3]);
  const Eigen::Isometry3d fk = ur::ForwardKinematics(options.model, options.initial_joints);
  EXPECT_LT((fk.translation() - Eigen::Vector3d(pose[0], pose[1], pose[2])).norm(), 1e-9);
  EXPECT_EQ(std::get<int32_t>(first.values[6]), kRobotModeRunning);
  EXPECT_EQ(std::get<int32_t>(first.values[7]), kSafetyModeNormal);
  EXPECT_EQ(std::get<uint32_t>(first.values[9]) & 1u, 1u);  // powered
  EXPECT_EQ(std::get<uint32_t>(first.values[10]), 1u);      // stopped
  EXPECT_EQ(std::get<double>(first.values[11]), 1.0);
  const ur::RtdeDataPackage second = next_package();
  EXPECT_GT(std::get<double>(second.values[0]), std::get<double>(first.values[0]));

  // A running program and the tool output show in the stream.
  emulator->controller().SubmitScript(
      "def hold():\n  set_tool_digital_out(1, True)\n  set_standard_digital_out(3, True)\n"
      "  sleep(1000)\nend\n");
  bool seen = false;
  for (int i = 0; i < 5000 && !seen; ++i) {
    const ur::RtdeDataPackage p = next_package();
    if (p.values.size() != names.size()) break;
    seen = std::get<uint64_t>(p.values[5]) == ((1u << 17) | (1u << 3)) &&
           (std::get<uint32_t>(p.values[9]) & 2u) && std::get<uint32_t>(p.values[10]) == 2u;
  }
  EXPECT_TRUE(seen);
  emulator->TriggerProtectiveStop();
  seen = false;
  for (int i = 0; i < 5000 && !seen; ++i) {
    const ur::RtdeDataPackage p = next_package();
    if (p.values.size() != names.size()) break;
    seen = (std::get<uint32_t>(p.values[8]) & 4u) &&
           std::get<int32_t>(p.values[7]) == kSafetyModeProtectiveStop &&
           std::get<uint32_t>(p.values[10]) == 1u;
  }
  EXPECT_TRUE(seen);

  accepted = ur::ParseAccepted(rtde.Exchange(ur::EncodePause(), T::kPause).payload);
  ASSERT_TRUE(accepted.ok());
  EXPECT_TRUE(*accepted);
}

TEST(UrEmulator, GarbageClosesOnlyThatConnection) {
  auto emulator = StartEmulator(FastOptions(/*powered=*/true));
  ASSERT_TRUE(emulator);
  // An RTDE size field below the header size cannot be resynchronised.
  ur::TcpConnection rtde = ConnectTo(emulator->rtde_port());
  ASSERT_TRUE(rtde.WriteAll(std::string("\x00\x01\x56", 3)).ok());
  auto read = rtde.Read(16, kTimeout);
  EXPECT_FALSE(read.ok());
  EXPECT_FALSE(absl::IsDeadlineExceeded(read.status())) << read.status();
  // A primary line longer than any script line.
  Primary primary(emulator->primary_port());
  primary.Send(std::string(100000, 'x'));
  EXPECT_FALSE(primary.ReadUntil([](const ur::PrimaryPackage&) { return false; }));
  // Binary bytes on the dashboard are just a command it does not know.
  Dashboard dashboard(emulator->dashboard_port());
  dashboard.Banner();
  EXPECT_THAT(dashboard.Send(std::string("\x01\xff", 2)), StartsWith("could not understand"));
  // The servers go on.
  Primary again(emulator->primary_port());
  again.Send("def fine():\n  sync()\nend\n");
  EXPECT_TRUE(again.ReadUntil(IsKey("PROGRAM_XXX_STOPPED", "fine")));
  EXPECT_EQ(emulator->Programs().size(), 1u);
}

TEST(UrEmulator, RejectsBadOptions) {
  UrEmulatorOptions options;
  options.time_scale = 0.0;
  EXPECT_EQ(UrEmulator::Start(options).status().code(), absl::StatusCode::kInvalidArgument);
}

TEST(UrEmulator, PortInUseIsAnError) {
  auto first = StartEmulator(FastOptions(true));
  ASSERT_TRUE(first);
  UrEmulatorOptions options = FastOptions(true);
  options.primary_port = first->primary_port();
  auto second = UrEmulator::Start(options);
  EXPECT_FALSE(second.ok());
}

}  // namespace
}  // namespace cornerpose::ur_emulator
