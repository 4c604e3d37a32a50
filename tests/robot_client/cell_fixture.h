// The whole cell on loopback, shared by the cell tests: the perception
// service replaying data/frames/cell, the UR controller emulator on its real
// TCP ports, and the daemon's parts started as cornerpose_robot_client
// starts them, with its status service for the test to read.
#pragma once

#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>

#include <chrono>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "absl/time/clock.h"
#include "absl/time/time.h"
#include "cornerpose/v1/robot_client_service.grpc.pb.h"
#include "robot_client/cell/cell_controller.h"
#include "robot_client/cell/perception_subscriber.h"
#include "robot_client/cell/status_service.h"
#include "robot_client/config/robot_config.h"
#include "server/server.h"
#include "tests/support/ur_emulator/ur_emulator.h"

namespace cornerpose::robot_client::testing {

inline std::string CellFramesDir() {
  return std::string(CORNERPOSE_SOURCE_DIR) + "/data/frames/cell";
}
inline std::string ShippedCellConfig() {
  return std::string(CORNERPOSE_SOURCE_DIR) + "/deploy/config/robot_client.textproto";
}

// Simulated seconds per wall second: a pick takes ~15 s simulated.
constexpr double kTimeScale = 20.0;

class CellFixture : public ::testing::Test {
 protected:
  void SetUp() override {
    const std::string kCellFrames = CellFramesDir();
    const std::string kConfig = ShippedCellConfig();
    server::ServerOptions server_options;
    server_options.listen_address = "127.0.0.1:0";
    server_options.sources = {{.name = "cell", .directory = kCellFrames, .fps = 10, .loop = true}};
    absl::StatusOr<std::unique_ptr<server::RunningServer>> server =
        server::StartServer(server_options);
    ASSERT_TRUE(server.ok()) << server.status();
    server_ = *std::move(server);

    ur_emulator::UrEmulatorOptions emulator_options;
    emulator_options.time_scale = kTimeScale;
    emulator_options.protective_stop_unlock_delay_s = 1.0;
    absl::StatusOr<std::unique_ptr<ur_emulator::UrEmulator>> emulator =
        ur_emulator::UrEmulator::Start(emulator_options);
    ASSERT_TRUE(emulator.ok()) << emulator.status();
    emulator_ = *std::move(emulator);

    absl::StatusOr<RobotClientOptions> options = LoadRobotClientConfig(kConfig);
    ASSERT_TRUE(options.ok()) << options.status();
    options_ = *std::move(options);
    options_.perception.server_address = "127.0.0.1:" + std::to_string(server_->port());
    options_.perception.source = "cell";
    // The recorded frames are a replay; these tests drive the emulator.
    options_.perception.allow_replay = true;
    options_.robot.host = "127.0.0.1";
    options_.robot.dashboard_port = emulator_->dashboard_port();
    options_.robot.primary_port = emulator_->primary_port();
    options_.robot.rtde_port = emulator_->rtde_port();
    options_.status_listen_address = "127.0.0.1:0";
    // The emulator starts powered off; these tests let the daemon bring it
    // up once at start (the operator's acknowledgement covers later ones).
    options_.robot.bring_up_at_start = true;
  }

  void TearDown() override {
    if (cell_) cell_->Stop();
    if (subscriber_) subscriber_->Stop();
    if (cell_thread_.joinable()) cell_thread_.join();
    status_server_.reset();
    cell_.reset();
    subscriber_.reset();
  }

  // Set: the subscription asks the server for this box size instead of the
  // one the cell plans for (a server and a daemon that disagree).
  std::optional<BoxDims> subscribed_box_;

  // Starts the daemon's parts as cornerpose_robot_client does.
  void StartCell() {
    PerceptionSubscriberOptions perception;
    perception.server = options_.perception.server_address;
    perception.source = options_.perception.source;
    perception.box_model = options_.perception.box_model;
    perception.box = subscribed_box_.value_or(options_.perception.box);
    perception.initial_backoff = absl::Milliseconds(100);
    perception.max_backoff = absl::Milliseconds(500);
    subscriber_ = std::make_unique<PerceptionSubscriber>(perception);
    CellControllerOptions controller;
    controller.retry_interval = absl::Milliseconds(100);
    controller.program_timeout = program_timeout_;
    CellCallbacks callbacks;
    callbacks.on_program = [this](const std::string& name, const std::string& text) {
      std::lock_guard<std::mutex> lock(programs_mutex_);
      rendered_programs_.push_back(name + "\n" + text);
    };
    cell_ = std::make_unique<CellController>(options_, controller, subscriber_.get(), callbacks);
    absl::StatusOr<std::unique_ptr<StatusServer>> status =
        StartStatusServer(options_.status_listen_address, cell_.get());
    ASSERT_TRUE(status.ok()) << status.status();
    status_server_ = *std::move(status);
    channel_ = grpc::CreateChannel("127.0.0.1:" + std::to_string(status_server_->port()),
                                   grpc::InsecureChannelCredentials());
    status_stub_ = v1::RobotClientService::NewStub(channel_);
    subscriber_->Start();
    cell_thread_ = std::thread([this] { cell_->Run(); });
  }

  // The cell's status through the status service.
  v1::CellStatus GetStatus() {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(5));
    v1::CellStatus status;
    const grpc::Status s = status_stub_->GetCellStatus(&context, {}, &status);
    EXPECT_TRUE(s.ok()) << s.error_message();
    return status;
  }

  // Polls the status service until `predicate` holds; false after `timeout`.
  bool WaitForStatus(const std::function<bool(const v1::CellStatus&)>& predicate,
                     absl::Duration timeout, v1::CellStatus* last = nullptr) {
    const absl::Time deadline = absl::Now() + timeout;
    v1::CellStatus status;
    while (absl::Now() < deadline) {
      status = GetStatus();
      if (predicate(status)) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    if (last) *last = status;
    return predicate(status);
  }

  // An operator's AcknowledgeFault through the status service.
  grpc::Status Acknowledge(const std::string& operator_name, bool unknown_pick_placed,
                           v1::AcknowledgeFaultResponse* response = nullptr) {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(5));
    v1::AcknowledgeFaultRequest request;
    request.set_operator_(operator_name);
    request.set_note("checked the cell");
    request.set_unknown_pick_placed(unknown_pick_placed);
    v1::AcknowledgeFaultResponse ignored;
    return status_stub_->AcknowledgeFault(&context, request, response ? response : &ignored);
  }

  // Waits for a program to be running on the emulator.
  bool WaitForProgramRunning(absl::Duration timeout) {
    return emulator_->WaitFor([](const ur_emulator::RobotSnapshot& s) { return s.program_running; },
                              timeout);
  }

  // True when no new program reaches the emulator for `d` (wall).
  bool NoProgramSentFor(absl::Duration d) {
    const size_t before = emulator_->Snapshot().programs_recorded;
    return !emulator_->WaitFor(
        [before](const ur_emulator::RobotSnapshot& s) { return s.programs_recorded > before; }, d);
  }

  std::vector<v1::PickRecord> ListPicks() {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(5));
    v1::ListPicksResponse response;
    const grpc::Status s = status_stub_->ListPicks(&context, {}, &response);
    EXPECT_TRUE(s.ok()) << s.error_message();
    return {response.picks().begin(), response.picks().end()};
  }

  // Every pick on record, one line each: what a failed wait prints (a pick
  // that ended otherwise than expected says why in its detail).
  std::string PicksText() {
    std::string text = "picks:\n";
    for (const v1::PickRecord& pick : ListPicks()) text += pick.ShortDebugString() + "\n";
    return text;
  }

  RobotClientOptions options_;
  // The daemon's limit on one pick program (tests of a hung program lower it).
  absl::Duration program_timeout_ = absl::Seconds(60);
  std::unique_ptr<server::RunningServer> server_;
  std::unique_ptr<ur_emulator::UrEmulator> emulator_;
  std::unique_ptr<PerceptionSubscriber> subscriber_;
  std::unique_ptr<CellController> cell_;
  std::unique_ptr<StatusServer> status_server_;
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<v1::RobotClientService::Stub> status_stub_;
  std::thread cell_thread_;
  std::mutex programs_mutex_;
  std::vector<std::string> rendered_programs_;
};

}  // namespace cornerpose::robot_client::testing
