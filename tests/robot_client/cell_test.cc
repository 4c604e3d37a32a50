// The whole cell on loopback: the perception service replays the bundled
// cell frames (data/frames/cell), the daemon subscribes over gRPC and drives
// the UR controller emulator over its real TCP interfaces (dashboard,
// primary, RTDE). What the emulator executed is checked against the frames'
// ground truth, the place pattern and the workspace, and the daemon's state
// is read through its own status service.
#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "absl/time/clock.h"
#include "absl/time/time.h"
#include "cornerpose/v1/robot_client_service.grpc.pb.h"
#include "grpc/health/v1/health.grpc.pb.h"
#include "robot_client/cell/cell_controller.h"
#include "robot_client/cell/perception_subscriber.h"
#include "robot_client/cell/status_service.h"
#include "robot_client/config/robot_config.h"
#include "robot_client/planning/place_pattern.h"
#include "robot_client/ur/dashboard_client.h"
#include "robot_client/ur/pose.h"
#include "server/server.h"
#include "tests/robot_client/cell_fixture.h"
#include "tests/support/ur_emulator/ur_emulator.h"

namespace cornerpose::robot_client {
namespace {

const std::string kSourceDir = CORNERPOSE_SOURCE_DIR;
const std::string kCellFrames = kSourceDir + "/data/frames/cell";

struct GroundTruthBox {
  Eigen::Isometry3d camera_T_box = Eigen::Isometry3d::Identity();
  Eigen::Vector3d dims = Eigen::Vector3d::Zero();
};

// The ground truth of every frame, in the order the directory source plays
// them (file names sorted).
std::vector<std::vector<GroundTruthBox>> LoadGroundTruth() {
  std::vector<std::string> files;
  for (const auto& entry : std::filesystem::directory_iterator(kCellFrames)) {
    if (entry.path().extension() == ".png") files.push_back(entry.path().stem().string());
  }
  std::sort(files.begin(), files.end());
  std::vector<std::vector<GroundTruthBox>> frames;
  for (const std::string& stem : files) {
    std::ifstream in(kCellFrames + "/" + stem + ".json");
    const nlohmann::json json = nlohmann::json::parse(in);
    std::vector<GroundTruthBox> boxes;
    for (const nlohmann::json& b : json["boxes"]) {
      GroundTruthBox box;
      for (int r = 0; r < 4; ++r) {
        for (int c = 0; c < 4; ++c)
          box.camera_T_box.matrix()(r, c) = b["T_cam_box"][r][c].get<double>();
      }
      box.dims = Eigen::Vector3d(b["dims"][0].get<double>(), b["dims"][1].get<double>(),
                                 b["dims"][2].get<double>());
      boxes.push_back(box);
    }
    frames.push_back(boxes);
  }
  return frames;
}

// How far `tcp` (a grasp pose in the base frame) is from lying on a face of
// `base_T_box`, in metres: the distance to the face plane, provided the point
// is within the face (plus a margin); and the angle between the tool z axis
// and the face's inward normal. Returns the best face.
struct FaceFit {
  double distance_m = 1e9;
  double angle_deg = 180.0;
};
FaceFit FitToFace(const Eigen::Isometry3d& base_T_tcp, const Eigen::Isometry3d& base_T_box,
                  const Eigen::Vector3d& dims) {
  const Eigen::Vector3d p = base_T_box.inverse() * base_T_tcp.translation();
  const Eigen::Vector3d half = 0.5 * dims;
  const Eigen::Vector3d tool_z = base_T_tcp.linear().col(2);
  FaceFit best;
  for (int axis = 0; axis < 3; ++axis) {
    for (double sign : {-1.0, 1.0}) {
      bool inside = true;
      for (int other = 0; other < 3; ++other) {
        if (other != axis && std::abs(p[other]) > half[other] + 0.01) inside = false;
      }
      if (!inside) continue;
      const double distance = std::abs(p[axis] - sign * half[axis]);
      const Eigen::Vector3d inward = -sign * base_T_box.linear().col(axis);
      const double angle = std::acos(std::clamp(tool_z.dot(inward), -1.0, 1.0)) * 180.0 / M_PI;
      if (distance < best.distance_m) best = {distance, angle};
    }
  }
  return best;
}

// The digital tool output 0 (the suction) after a step.
bool SuctionOn(const ur_emulator::ExecutedStep& step) { return (step.tool_outputs & 1u) != 0; }

class CellTest : public testing::CellFixture {};

TEST_F(CellTest, PicksRealBoxesAndPlacesThemSlotBySlot) {
  constexpr int kPicks = 4;
  options_.max_picks = kPicks;
  StartCell();
  v1::CellStatus status;
  ASSERT_TRUE(
      WaitForStatus([](const v1::CellStatus& s) { return s.state() == v1::CELL_STATE_FINISHED; },
                    absl::Seconds(180), &status))
      << status.DebugString();
  EXPECT_EQ(status.picks_done(), static_cast<uint32_t>(kPicks));
  EXPECT_EQ(status.picks_failed(), 0u);
  EXPECT_EQ(status.next_slot(), static_cast<uint32_t>(kPicks));

  const std::vector<v1::PickRecord> picks = ListPicks();
  const std::vector<ur_emulator::ExecutedProgram> programs = emulator_->Programs();
  ASSERT_EQ(picks.size(), static_cast<size_t>(kPicks));
  ASSERT_EQ(programs.size(), static_cast<size_t>(kPicks));
  const std::vector<std::vector<GroundTruthBox>> truth = LoadGroundTruth();
  ASSERT_EQ(truth.size(), 8u);

  for (int k = 0; k < kPicks; ++k) {
    SCOPED_TRACE("pick " + std::to_string(k + 1));
    const v1::PickRecord& pick = picks[static_cast<size_t>(k)];
    const ur_emulator::ExecutedProgram& program = programs[static_cast<size_t>(k)];
    EXPECT_EQ(pick.outcome(), v1::PICK_OUTCOME_COMPLETED) << pick.detail();
    EXPECT_EQ(program.name, pick.program_name());
    ASSERT_EQ(program.outcome, ur_emulator::ProgramOutcome::kCompleted) << program.error_text;

    // Suction on exactly from the grasp G to the place F: off before the
    // step that switches it on, on through the moves that carry the box,
    // off from the step that switches it off.
    int on = -1, off = -1;
    for (size_t i = 0; i < program.steps.size(); ++i) {
      const bool is_set = program.steps[i].kind == "set_tool_digital_out";
      if (is_set && on < 0 && SuctionOn(program.steps[i])) on = static_cast<int>(i);
      if (is_set && on >= 0 && off < 0 && !SuctionOn(program.steps[i])) off = static_cast<int>(i);
    }
    ASSERT_GT(on, 0);
    ASSERT_GT(off, on);
    for (int i = 0; i < static_cast<int>(program.steps.size()); ++i) {
      EXPECT_EQ(SuctionOn(program.steps[static_cast<size_t>(i)]), i >= on && i < off)
          << "step " << i << " " << program.steps[static_cast<size_t>(i)].kind;
    }
    // Where the arm was when the suction went on is G; when it went off, F.
    const Eigen::Isometry3d base_T_g = ur::FromUrPose(program.steps[static_cast<size_t>(on)].tcp);
    const Eigen::Isometry3d base_T_f = ur::FromUrPose(program.steps[static_cast<size_t>(off)].tcp);
    const ur_emulator::ExecutedStep& before_on = program.steps[static_cast<size_t>(on - 1)];
    EXPECT_EQ(before_on.kind, "movel");  // M -> G is a straight move

    // G lies on a face of a real box of the frame the daemon used, tool
    // pointing into it.
    const std::vector<GroundTruthBox>& frame = truth[(pick.frame_id() - 1) % truth.size()];
    FaceFit best;
    for (const GroundTruthBox& box : frame) {
      const FaceFit fit = FitToFace(base_T_g, options_.base_T_camera * box.camera_T_box, box.dims);
      if (fit.distance_m < best.distance_m) best = fit;
    }
    EXPECT_LT(best.distance_m, 0.010);
    EXPECT_LT(best.angle_deg, 5.0);

    // F: the box's bottom centre on slot k, so the TCP is straight above it.
    absl::StatusOr<Eigen::Isometry3d> slot = SlotPose(options_.place_pattern, k);
    ASSERT_TRUE(slot.ok());
    EXPECT_LT((base_T_f.translation().head<2>() - slot->translation().head<2>()).norm(), 0.002);
    EXPECT_EQ(pick.slot(), static_cast<uint32_t>(k));

    // Nothing commanded outside the workspace.
    for (const ur_emulator::ExecutedStep& step : program.steps) {
      if (!step.target) continue;
      EXPECT_TRUE(options_.workspace.Contains(step.target->position))
          << step.kind << " to " << step.target->position.transpose();
    }
    // No frame captured before the previous program ended.
    if (k > 0) {
      const v1::PickRecord& previous = picks[static_cast<size_t>(k - 1)];
      const double previous_end_ns =
          static_cast<double>(previous.start_time_unix_nanos()) + previous.program_s() * 1e9;
      EXPECT_GT(static_cast<double>(pick.capture_time_unix_nanos()), previous_end_ns);
      // And by the source's own frame order: past the frame in flight when
      // the previous move ended.
      EXPECT_GE(pick.frame_id(), previous.frame_id() + 2);
    }
  }

  // The daemon is healthy through standard gRPC health checking.
  auto health = grpc::health::v1::Health::NewStub(channel_);
  grpc::ClientContext context;
  grpc::health::v1::HealthCheckResponse response;
  ASSERT_TRUE(health->Check(&context, {}, &response).ok());
  EXPECT_EQ(response.status(), grpc::health::v1::HealthCheckResponse::SERVING);
}

TEST_F(CellTest, ProtectiveStopHaltsThePickAndAReleaseResumes) {
  options_.max_picks = 2;
  StartCell();
  // Mid-pick: the box is held (suction on) and the arm is moving.
  ASSERT_TRUE(emulator_->WaitFor(
      [](const ur_emulator::RobotSnapshot& s) {
        return s.program_running && (s.tool_outputs & 1u) != 0;
      },
      absl::Seconds(60)));
  emulator_->TriggerProtectiveStop();

  v1::CellStatus status;
  ASSERT_TRUE(WaitForStatus(
      [](const v1::CellStatus& s) {
        return s.state() == v1::CELL_STATE_STOPPED &&
               s.stop_reason().find("PROTECTIVE_STOP") != std::string::npos;
      },
      absl::Seconds(30), &status))
      << status.DebugString();
  // While stopped, nothing is sent.
  const size_t programs_at_stop = emulator_->Snapshot().programs_recorded;
  std::this_thread::sleep_for(std::chrono::seconds(1));
  EXPECT_EQ(emulator_->Snapshot().programs_recorded, programs_at_stop);
  EXPECT_EQ(GetStatus().state(), v1::CELL_STATE_STOPPED);

  // The operator releases the stop on the dashboard, as on a real cell
  // (refused until the unlock delay has passed).
  ur::DashboardClient dashboard;
  ASSERT_TRUE(dashboard.Connect("127.0.0.1", emulator_->dashboard_port()).ok());
  bool released = false;
  for (int i = 0; i < 400 && !released; ++i) {  // 20 s: a loaded machine
    released = dashboard.UnlockProtectiveStop().ok();
    if (!released) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  ASSERT_TRUE(released);

  // The box is still on the cup: the cell stays stopped until the operator
  // has cleared it and switched the vacuum off (here from the controller,
  // as from its teach pendant).
  ASSERT_TRUE(WaitForStatus(
      [](const v1::CellStatus& s) {
        return s.state() == v1::CELL_STATE_STOPPED &&
               s.stop_reason().find("suction output is on") != std::string::npos;
      },
      absl::Seconds(30), &status))
      << status.DebugString();
  EXPECT_EQ(emulator_->Snapshot().programs_recorded, programs_at_stop);
  emulator_->controller().SubmitScript(
      "def operator_clear():\n  set_tool_digital_out(0, False)\nend\n");

  ASSERT_TRUE(
      WaitForStatus([](const v1::CellStatus& s) { return s.state() == v1::CELL_STATE_FINISHED; },
                    absl::Seconds(120), &status))
      << status.DebugString();
  EXPECT_EQ(status.picks_done(), 2u);
  EXPECT_EQ(status.picks_failed(), 1u);
  const std::vector<v1::PickRecord> picks = ListPicks();
  std::string log;
  for (const v1::PickRecord& pick : picks) log += pick.ShortDebugString() + "\n";
  ASSERT_EQ(picks.size(), 3u) << log;
  EXPECT_EQ(picks[0].outcome(), v1::PICK_OUTCOME_PROTECTIVE_STOP);
  EXPECT_EQ(picks[1].outcome(), v1::PICK_OUTCOME_COMPLETED);
  // The stopped pick did not take the slot: the next pick goes to slot 0.
  EXPECT_EQ(picks[1].slot(), 0u);
  const std::vector<ur_emulator::ExecutedProgram> programs = emulator_->Programs();
  ASSERT_EQ(programs.size(), 4u);  // the two picks around the operator's program
  EXPECT_EQ(programs[0].outcome, ur_emulator::ProgramOutcome::kProtectiveStop);
  EXPECT_EQ(programs[1].name, "operator_clear");
}

TEST_F(CellTest, LostPerceptionStreamStopsTheCellUntilTheServiceReturns) {
  options_.max_picks = 2;
  StartCell();
  ASSERT_TRUE(WaitForStatus([](const v1::CellStatus& s) { return s.perception_connected(); },
                            absl::Seconds(30)));
  const int port = server_->port();
  server_->Shutdown();
  server_.reset();
  v1::CellStatus status;
  ASSERT_TRUE(WaitForStatus(
      [](const v1::CellStatus& s) {
        return s.state() == v1::CELL_STATE_STOPPED &&
               s.stop_reason().find("perception stream lost") != std::string::npos;
      },
      absl::Seconds(30), &status))
      << status.DebugString();

  // The service comes back on the same address; the daemon reconnects.
  server::ServerOptions server_options;
  server_options.listen_address = "127.0.0.1:" + std::to_string(port);
  server_options.sources = {{.name = "cell", .directory = kCellFrames, .fps = 10, .loop = true}};
  absl::StatusOr<std::unique_ptr<server::RunningServer>> server =
      server::StartServer(server_options);
  ASSERT_TRUE(server.ok()) << server.status();
  server_ = *std::move(server);
  ASSERT_TRUE(
      WaitForStatus([](const v1::CellStatus& s) { return s.state() == v1::CELL_STATE_FINISHED; },
                    absl::Seconds(120), &status))
      << status.DebugString();
  EXPECT_EQ(status.picks_done(), 2u);
}

TEST_F(CellTest, DroppedControllerConnectionsAreReopened) {
  options_.max_picks = 2;
  StartCell();
  ASSERT_TRUE(WaitForStatus([](const v1::CellStatus& s) { return s.picks_done() >= 1; },
                            absl::Seconds(120)));
  emulator_->DropConnections();
  v1::CellStatus status;
  ASSERT_TRUE(WaitForStatus(
      [](const v1::CellStatus& s) {
        return s.state() == v1::CELL_STATE_FINISHED || s.unknown_pick_id() != 0;
      },
      absl::Seconds(120), &status))
      << status.DebugString();
  if (status.unknown_pick_id() != 0) {
    // The drop hit a running pick: its end is unknown, the daemon stopped
    // the program on reconnect and sends nothing until an operator answers.
    EXPECT_EQ(status.state(), v1::CELL_STATE_STOPPED);
    ASSERT_TRUE(WaitForStatus([](const v1::CellStatus& s) { return s.awaiting_acknowledgement(); },
                              absl::Seconds(30), &status))
        << status.DebugString();
    EXPECT_FALSE(emulator_->Snapshot().program_running);
    EXPECT_TRUE(NoProgramSentFor(absl::Seconds(1)));
    ASSERT_TRUE(Acknowledge("ada", /*unknown_pick_placed=*/false).ok());
  }
  ASSERT_TRUE(
      WaitForStatus([](const v1::CellStatus& s) { return s.state() == v1::CELL_STATE_FINISHED; },
                    absl::Seconds(120), &status))
      << status.DebugString();
  EXPECT_EQ(status.picks_done(), 2u);
}

TEST_F(CellTest, DryRunRendersProgramsWithoutSendingThem) {
  options_.max_picks = 2;
  options_.dry_run = true;
  StartCell();
  v1::CellStatus status;
  ASSERT_TRUE(
      WaitForStatus([](const v1::CellStatus& s) { return s.state() == v1::CELL_STATE_FINISHED; },
                    absl::Seconds(60), &status))
      << status.DebugString();
  EXPECT_TRUE(status.dry_run());
  EXPECT_EQ(emulator_->Snapshot().programs_recorded, 0u);
  const std::vector<v1::PickRecord> picks = ListPicks();
  ASSERT_EQ(picks.size(), 2u);
  EXPECT_EQ(picks[0].outcome(), v1::PICK_OUTCOME_DRY_RUN);
  std::lock_guard<std::mutex> lock(programs_mutex_);
  ASSERT_EQ(rendered_programs_.size(), 2u);
  EXPECT_NE(rendered_programs_[0].find("def pick_0001():"), std::string::npos);
}

}  // namespace
}  // namespace cornerpose::robot_client
