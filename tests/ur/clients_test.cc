// The dashboard, primary and RTDE clients against small real servers on
// loopback written here (the full controller emulator has its own tests).
#include <gtest/gtest.h>

#include <functional>
#include <map>
#include <mutex>
#include <thread>

#include "robot_client/ur/dashboard_client.h"
#include "robot_client/ur/primary.h"
#include "robot_client/ur/primary_client.h"
#include "robot_client/ur/rtde.h"
#include "robot_client/ur/rtde_client.h"
#include "robot_client/ur/tcp.h"
#include "tests/ur/test_data.h"

namespace cornerpose::ur {
namespace {

constexpr absl::Duration kLong = absl::Seconds(20);  // never reached when all is well

// Accepts one connection and runs `handler` on it in a thread. The
// destructor shuts the connection down, so a handler blocked in a read ends.
class OneShotServer {
 public:
  explicit OneShotServer(std::function<void(TcpConnection&)> handler) {
    absl::StatusOr<TcpListener> listener = TcpListener::Listen("127.0.0.1", 0);
    EXPECT_TRUE(listener.ok()) << listener.status();
    listener_ = std::move(*listener);
    thread_ = std::thread([this, handler = std::move(handler)] {
      absl::StatusOr<TcpConnection> c = listener_.Accept(kLong);
      if (!c.ok()) return;
      {
        std::lock_guard<std::mutex> lock(mutex_);
        connection_ = std::move(*c);
        if (stopping_) return;
      }
      handler(connection_);
      // The handler is done: the peer sees the connection close.
      std::lock_guard<std::mutex> lock(mutex_);
      connection_.Close();
    });
  }
  ~OneShotServer() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stopping_ = true;
      connection_.Shutdown();
    }
    listener_.Close();
    thread_.join();
  }
  int port() const { return listener_.port(); }

 private:
  TcpListener listener_;
  std::mutex mutex_;
  bool stopping_ = false;
  TcpConnection connection_;
  std::thread thread_;
};

// ---- Dashboard ----

struct FakeDashboard {
  std::mutex mutex;
  std::vector<std::string> commands;
  std::string mode = "POWER_OFF";

  void Serve(TcpConnection& c) {
    if (!c.WriteAll("Connected: Universal Robots Dashboard Server\n").ok()) return;
    while (true) {
      absl::StatusOr<std::string> line = c.ReadLine(kLong);
      if (!line.ok()) return;
      std::string reply;
      {
        std::lock_guard<std::mutex> lock(mutex);
        commands.push_back(*line);
        if (*line == "robotmode") {
          reply = "Robotmode: " + mode;
        } else if (*line == "power on") {
          reply = "Powering on";
          mode = "IDLE";
        } else if (*line == "brake release") {
          reply = "Brake releasing";
          mode = "RUNNING";
        } else if (*line == "safetymode") {
          reply = "Safetymode: PROTECTIVE_STOP";
        } else if (*line == "unlock protective stop") {
          reply = "Protective stop releasing";
        } else if (*line == "running") {
          reply = "Program running: false";
        } else if (*line == "stop") {
          reply = "Failed to execute: stop";
        } else {
          reply = "could not understand: '" + *line + "'";
        }
      }
      if (!c.WriteAll(reply + "\n").ok()) return;
    }
  }
};

TEST(DashboardClient, BringUpAndCommands) {
  FakeDashboard fake;
  OneShotServer server([&](TcpConnection& c) { fake.Serve(c); });
  DashboardClient client(DashboardOptions{.poll_interval = absl::Milliseconds(1)});
  ASSERT_TRUE(client.Connect("127.0.0.1", server.port(), kLong).ok());
  EXPECT_TRUE(client.connected());
  EXPECT_EQ(*client.RobotMode(), RobotMode::kPowerOff);
  ASSERT_TRUE(client.BringUp(kLong).ok());
  EXPECT_EQ(*client.RobotMode(), RobotMode::kRunning);
  // safetystatus is not understood here: falls back to safetymode.
  absl::StatusOr<SafetyMode> safety = client.SafetyStatus();
  ASSERT_TRUE(safety.ok()) << safety.status();
  EXPECT_EQ(*safety, SafetyMode::kProtectiveStop);
  EXPECT_TRUE(client.UnlockProtectiveStop().ok());
  EXPECT_FALSE(*client.ProgramRunning());
  const absl::Status stop = client.Stop();
  EXPECT_EQ(stop.code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_NE(stop.message().find("Failed to execute"), std::string::npos);
  std::lock_guard<std::mutex> lock(fake.mutex);
  const std::vector<std::string> expected = {
      "robotmode", "robotmode", "power on",     "robotmode",  "brake release",
      "robotmode", "robotmode", "safetystatus", "safetymode", "unlock protective stop",
      "running",   "stop"};
  EXPECT_EQ(fake.commands, expected);
}

TEST(DashboardClient, WrongBannerAndNoServer) {
  OneShotServer server([](TcpConnection& c) { (void)c.WriteAll("SSH-2.0-OpenSSH\n"); });
  DashboardClient client;
  EXPECT_EQ(client.Connect("127.0.0.1", server.port(), kLong).code(),
            absl::StatusCode::kFailedPrecondition);
  EXPECT_FALSE(client.connected());
  EXPECT_EQ(client.RobotMode().status().code(), absl::StatusCode::kUnavailable);
}

TEST(DashboardClient, ServerGoneIsUnavailable) {
  OneShotServer server(
      [](TcpConnection& c) { (void)c.WriteAll("Connected: Universal Robots Dashboard Server\n"); });
  DashboardClient client;
  ASSERT_TRUE(client.Connect("127.0.0.1", server.port(), kLong).ok());
  EXPECT_EQ(client.Command("robotmode", kLong).status().code(), absl::StatusCode::kUnavailable);
  EXPECT_FALSE(client.connected());
}

// ---- Primary ----

// Reads one script (up to a line "end") and returns it, "" on error.
std::string ReadScript(TcpConnection& c) {
  std::string script;
  while (true) {
    absl::StatusOr<std::string> line = c.ReadLine(kLong);
    if (!line.ok()) return "";
    script += *line + "\n";
    if (*line == "end") return script;
  }
}

KeyMessage Key(absl::string_view title, absl::string_view name) {
  KeyMessage k;
  k.title = std::string(title);
  k.text = std::string(name);
  return k;
}

TEST(PrimaryClient, ProgramCompletes) {
  const std::string state = ReadTestFile("ur5e_ursim5.8_primary_robot_state.bin");
  std::string received;
  OneShotServer server([&](TcpConnection& c) {
    VersionMessage v;
    (void)c.WriteAll(EncodeVersionMessage(v) + state);
    received = ReadScript(c);
    TextMessage t;
    t.text = "hello";
    (void)c.WriteAll(EncodeKeyMessage(Key("PROGRAM_XXX_STARTED", "other")) +
                     EncodeKeyMessage(Key("PROGRAM_XXX_STARTED", "job_1")) + EncodeTextMessage(t) +
                     EncodeKeyMessage(Key("PROGRAM_XXX_STOPPED", "other")) + state +
                     EncodeKeyMessage(Key("PROGRAM_XXX_STOPPED", "job_1")));
    (void)c.Read(1, kLong);  // until the client goes
  });
  PrimaryClient client;
  ASSERT_TRUE(client.Connect("127.0.0.1", server.port(), kLong).ok());
  ASSERT_TRUE(client.WaitForStateCount(0, kLong));
  const std::optional<RobotState> latest = client.LatestState();
  ASSERT_TRUE(latest && latest->joints);
  EXPECT_EQ(ActualJoints(*latest->joints)[0], -1.6006999999999998);
  ASSERT_TRUE(client.version().has_value());
  EXPECT_EQ(client.version()->project_name, "URControl");

  ASSERT_TRUE(client.SendScript("def job_1():\n  textmsg(\"hello\")\nend").ok());
  const ProgramOutcome outcome = client.WaitForProgram("job_1", kLong);
  EXPECT_EQ(outcome.kind, ProgramOutcome::kCompleted) << outcome.detail;
  EXPECT_TRUE(outcome.started);
  EXPECT_EQ(outcome.text_messages, std::vector<std::string>{"hello"});
  EXPECT_EQ(received, "def job_1():\n  textmsg(\"hello\")\nend\n");
  EXPECT_TRUE(client.connected());
}

TEST(PrimaryClient, RuntimeException) {
  OneShotServer server([&](TcpConnection& c) {
    if (ReadScript(c).empty()) return;
    RuntimeExceptionMessage e;
    e.line = 2;
    e.column = 3;
    e.text = "compile_error_name_not_found:calldoesntexist:";
    (void)c.WriteAll(EncodeRuntimeExceptionMessage(e));
    (void)c.Read(1, kLong);
  });
  PrimaryClient client;
  ASSERT_TRUE(client.Connect("127.0.0.1", server.port(), kLong).ok());
  ASSERT_TRUE(client.SendScript("def bad():\n  calldoesntexist()\nend\n").ok());
  const ProgramOutcome outcome = client.WaitForProgram("bad", kLong);
  EXPECT_EQ(outcome.kind, ProgramOutcome::kRuntimeException);
  EXPECT_NE(outcome.detail.find("calldoesntexist"), std::string::npos) << outcome.detail;
  EXPECT_NE(outcome.detail.find("line 2"), std::string::npos) << outcome.detail;
}

TEST(PrimaryClient, ProtectiveStopFromRobotModeData) {
  OneShotServer server([&](TcpConnection& c) {
    if (ReadScript(c).empty()) return;
    RobotState s;
    s.robot_mode.emplace();
    s.robot_mode->protective_stopped = true;
    (void)c.WriteAll(EncodeKeyMessage(Key("PROGRAM_XXX_STARTED", "job")) + EncodeRobotState(s));
    (void)c.Read(1, kLong);
  });
  PrimaryClient client;
  ASSERT_TRUE(client.Connect("127.0.0.1", server.port(), kLong).ok());
  ASSERT_TRUE(client.SendScript("def job():\n  movej([0,0,0,0,0,0])\nend\n").ok());
  const ProgramOutcome outcome = client.WaitForProgram("job", kLong);
  EXPECT_EQ(outcome.kind, ProgramOutcome::kProtectiveStop) << outcome.detail;
  EXPECT_TRUE(outcome.started);
}

TEST(PrimaryClient, ProtectiveStopFromSafetyModeMessage) {
  OneShotServer server([&](TcpConnection& c) {
    if (ReadScript(c).empty()) return;
    SafetyModeMessage m;
    m.safety_mode = static_cast<uint8_t>(SafetyMode::kProtectiveStop);
    (void)c.WriteAll(EncodeSafetyModeMessage(m));
    (void)c.Read(1, kLong);
  });
  PrimaryClient client;
  ASSERT_TRUE(client.Connect("127.0.0.1", server.port(), kLong).ok());
  ASSERT_TRUE(client.SendScript("def job():\nend\n").ok());
  const ProgramOutcome outcome = client.WaitForProgram("job", kLong);
  EXPECT_EQ(outcome.kind, ProgramOutcome::kProtectiveStop);
  EXPECT_NE(outcome.detail.find("PROTECTIVE_STOP"), std::string::npos) << outcome.detail;
}

TEST(PrimaryClient, ConnectionLostAndTimeout) {
  {
    OneShotServer server([&](TcpConnection& c) { (void)ReadScript(c); });
    PrimaryClient client;
    ASSERT_TRUE(client.Connect("127.0.0.1", server.port(), kLong).ok());
    ASSERT_TRUE(client.SendScript("def job():\nend\n").ok());
    const ProgramOutcome outcome = client.WaitForProgram("job", kLong);
    EXPECT_EQ(outcome.kind, ProgramOutcome::kConnectionLost) << outcome.detail;
    EXPECT_FALSE(client.connected());
    EXPECT_EQ(client.SendScript("def job():\nend\n").code(), absl::StatusCode::kUnavailable);
  }
  {
    OneShotServer server([&](TcpConnection& c) {
      (void)ReadScript(c);
      (void)c.Read(1, kLong);
    });
    PrimaryClient client;
    ASSERT_TRUE(client.Connect("127.0.0.1", server.port(), kLong).ok());
    ASSERT_TRUE(client.SendScript("def job():\nend\n").ok());
    const ProgramOutcome outcome = client.WaitForProgram("job", absl::Milliseconds(30));
    EXPECT_EQ(outcome.kind, ProgramOutcome::kTimeout);
    EXPECT_FALSE(outcome.started);
  }
}

TEST(PrimaryClient, GarbageStreamDisconnects) {
  OneShotServer server([&](TcpConnection& c) {
    (void)c.WriteAll(std::string("\x00\x00\x00\x01\x10", 5));  // impossible length
    (void)c.Read(1, kLong);
  });
  PrimaryClient client;
  ASSERT_TRUE(client.Connect("127.0.0.1", server.port(), kLong).ok());
  const ProgramOutcome outcome = client.WaitForProgram("job", kLong);
  EXPECT_EQ(outcome.kind, ProgramOutcome::kConnectionLost);
  EXPECT_EQ(client.connection_status().code(), absl::StatusCode::kDataLoss);
}

// ---- RTDE ----

struct FakeRtdeOptions {
  bool refuse_variable = false;
  int packages = 3;
};

void ServeRtde(TcpConnection& c, FakeRtdeOptions options, std::vector<std::string>* names) {
  RtdeFramer framer;
  int started = 0;
  while (started == 0) {
    absl::StatusOr<std::optional<RtdeFrame>> f = framer.Next();
    if (!f.ok()) return;
    if (!f->has_value()) {
      absl::StatusOr<std::string> bytes = c.Read(4096, kLong);
      if (!bytes.ok()) return;
      framer.Append(*bytes);
      continue;
    }
    const RtdeFrame& frame = **f;
    std::string reply;
    switch (static_cast<RtdeMessageType>(frame.type)) {
      case RtdeMessageType::kRequestProtocolVersion:
        reply = EncodeRtdeTextMessage({"welcome", "fake", 3}) +
                EncodeAccepted(RtdeMessageType::kRequestProtocolVersion,
                               *ParseRequestProtocolVersion(frame.payload) == 2);
        break;
      case RtdeMessageType::kGetUrcontrolVersion:
        reply = EncodeUrcontrolVersion({5, 8, 0, 0});
        break;
      case RtdeMessageType::kSetupOutputs: {
        SetupOutputsRequest request = *ParseSetupOutputs(frame.payload);
        *names = request.names;
        SetupReply r{1, {}};
        for (const std::string& n : request.names) {
          const bool refused = options.refuse_variable && n == "safety_status_bits";
          if (refused || !RtdeOutputType(n).has_value()) {
            r.types.push_back("NOT_FOUND");
            r.recipe_id = 0;
          } else {
            r.types.push_back(RtdeTypeName(*RtdeOutputType(n)));
          }
        }
        reply = EncodeSetupReply(RtdeMessageType::kSetupOutputs, r);
        break;
      }
      case RtdeMessageType::kStart:
        reply = EncodeAccepted(RtdeMessageType::kStart, true);
        started = 1;
        break;
      default:
        return;
    }
    if (!c.WriteAll(reply).ok()) return;
  }
  for (int i = 1; i <= options.packages; ++i) {
    RtdeDataPackage p{1, {}};
    for (const std::string& n : *names) {
      const RtdeType t = *RtdeOutputType(n);
      if (n == "timestamp") {
        p.values.emplace_back(double(i));
      } else if (n == "actual_q") {
        p.values.emplace_back(std::array<double, 6>{0.1 * i, 0.2, 0.3, 0.4, 0.5, 0.6});
      } else if (n == "actual_TCP_pose") {
        p.values.emplace_back(std::array<double, 6>{0.5, -0.1, 0.3, 0.0, 3.14, 0.0});
      } else if (n == "actual_digital_output_bits") {
        p.values.emplace_back(uint64_t{0x10005});
      } else if (n == "robot_mode") {
        p.values.emplace_back(int32_t{7});
      } else if (n == "safety_mode") {
        p.values.emplace_back(int32_t{1});
      } else if (n == "safety_status_bits") {
        p.values.emplace_back(uint32_t{1});
      } else if (n == "runtime_state") {
        p.values.emplace_back(uint32_t{2});
      } else if (t == RtdeType::kVector6d) {
        p.values.emplace_back(std::array<double, 6>{});
      } else if (t == RtdeType::kDouble) {
        p.values.emplace_back(1.0);
      } else if (t == RtdeType::kUint64) {
        p.values.emplace_back(uint64_t{0});
      } else if (t == RtdeType::kUint32) {
        p.values.emplace_back(uint32_t{0});
      } else {
        p.values.emplace_back(int32_t{0});
      }
    }
    if (!c.WriteAll(EncodeDataPackage(p)).ok()) return;
  }
}

TEST(RtdeClient, HandshakeAndData) {
  std::vector<std::string> names;
  std::mutex done_mutex;
  std::condition_variable done;
  bool close_now = false;
  OneShotServer server([&](TcpConnection& c) {
    ServeRtde(c, {}, &names);
    std::unique_lock<std::mutex> lock(done_mutex);
    done.wait_for(lock, std::chrono::seconds(20), [&] { return close_now; });
  });
  RtdeClient client;
  ASSERT_TRUE(client.Connect("127.0.0.1", server.port(), kLong).ok());
  EXPECT_EQ(names, RtdeClientOutputs());
  ASSERT_TRUE(client.controller_version().has_value());
  EXPECT_EQ(client.controller_version()->minor, 8u);
  absl::StatusOr<RtdeState> s = client.Latest();
  ASSERT_TRUE(s.ok()) << s.status();
  EXPECT_GE(s->sequence, 1u);
  s = client.WaitForNewer(2, kLong);
  ASSERT_TRUE(s.ok()) << s.status();
  EXPECT_EQ(s->sequence, 3u);
  EXPECT_EQ(s->timestamp, 3.0);
  EXPECT_NEAR(s->actual_q[0], 0.3, 1e-15);
  EXPECT_EQ(s->actual_q[5], 0.6);
  EXPECT_EQ(s->actual_tcp_pose.position, Eigen::Vector3d(0.5, -0.1, 0.3));
  EXPECT_EQ(s->actual_tcp_pose.rotation, Eigen::Vector3d(0.0, 3.14, 0.0));
  EXPECT_EQ(s->digital_outputs, 0x10005u);
  EXPECT_EQ(s->robot_mode, 7);
  EXPECT_EQ(s->safety_mode, 1);
  EXPECT_EQ(s->safety_status_bits, 1u);
  EXPECT_EQ(s->runtime_state, 2u);
  EXPECT_EQ(client.WaitForNewer(3, absl::Milliseconds(20)).status().code(),
            absl::StatusCode::kDeadlineExceeded);
  {
    std::lock_guard<std::mutex> lock(done_mutex);
    close_now = true;
  }
  done.notify_all();
  // The server ends: the client notices.
  EXPECT_EQ(client.WaitForNewer(3, kLong).status().code(), absl::StatusCode::kUnavailable);
  EXPECT_EQ(client.Latest().status().code(), absl::StatusCode::kUnavailable);
  EXPECT_FALSE(client.connected());
}

TEST(RtdeClient, RefusedVariableFailsConnect) {
  std::vector<std::string> names;
  OneShotServer server([&](TcpConnection& c) { ServeRtde(c, {.refuse_variable = true}, &names); });
  RtdeClient client;
  const absl::Status s = client.Connect("127.0.0.1", server.port(), kLong);
  EXPECT_EQ(s.code(), absl::StatusCode::kNotFound) << s;
  EXPECT_NE(s.message().find("safety_status_bits"), std::string::npos) << s;
  EXPECT_EQ(client.Latest().status().code(), absl::StatusCode::kUnavailable);
}

TEST(RtdeClient, NoServer) {
  int port = 0;
  {
    absl::StatusOr<TcpListener> l = TcpListener::Listen("127.0.0.1", 0);
    ASSERT_TRUE(l.ok());
    port = l->port();
  }
  RtdeClient client;
  EXPECT_EQ(client.Connect("127.0.0.1", port, kLong).code(), absl::StatusCode::kUnavailable);
  PrimaryClient primary;
  EXPECT_EQ(primary.Connect("127.0.0.1", port, kLong).code(), absl::StatusCode::kUnavailable);
  DashboardClient dashboard;
  EXPECT_EQ(dashboard.Connect("127.0.0.1", port, kLong).code(), absl::StatusCode::kUnavailable);
}

}  // namespace
}  // namespace cornerpose::ur
