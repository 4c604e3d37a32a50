// The simulated cell's world against the emulated controller running
// URScript: suction grips the face under the cup (and only that), the box
// follows the tool and is set down where the vacuum goes off, a bad grip
// loses the box on the way up, a pinned box stays, contact is a protective
// stop, and the camera shows the change.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <memory>
#include <string>

#include "absl/strings/str_format.h"
#include "common/io/png_io.h"
#include "robot_client/ur/kinematics.h"
#include "robot_client/ur/pose.h"
#include "tests/support/cell_sim/sim_camera.h"
#include "tests/support/cell_sim/sim_cell.h"
#include "tests/support/ur_emulator/controller.h"

namespace cornerpose::cell_sim {
namespace {

class CellWorldTest : public ::testing::Test {
 protected:
  void SetUp() override {
    SimLoadOptions load;
    load.layers = 2;
    load.seed = 3;
    absl::StatusOr<SimCell> cell = MakeSimCell({}, load);
    ASSERT_TRUE(cell.ok()) << cell.status();
    cell_ = *std::move(cell);
    world_ = std::make_shared<CellWorld>(cell_.layout, cell_.boxes, CellWorldOptions{});
    ur_emulator::UrEmulatorOptions options;
    options.time_scale = 50.0;
    options.start_powered_off = false;
    options.world = world_;
    controller_ = std::make_unique<ur_emulator::Controller>(options);
  }

  // base_T_tcp with the tool pointing down at world point p (+ dz up).
  std::string DownAt(const Eigen::Vector3d& world_p, double dz = 0.0) const {
    Eigen::Isometry3d tcp = Eigen::Isometry3d::Identity();
    tcp.linear() << 1, 0, 0, 0, -1, 0, 0, 0, -1;
    tcp.translation() = cell_.layout.world_T_base.inverse() * (world_p + Eigen::Vector3d(0, 0, dz));
    return ur::FormatPoseLiteral(ur::ToUrPose(tcp));
  }

  // The top face centre of box i, world.
  Eigen::Vector3d TopOf(int i) const {
    // Boxes() returns a copy: keep the box, not a reference into it.
    const SimBox box = world_->Boxes()[static_cast<size_t>(i)];
    return box.world_T_box * Eigen::Vector3d(0, 0, 0.5 * box.dims.h);
  }

  // The top layer's boxes are the last ones.
  int TopBox() const { return static_cast<int>(cell_.boxes.size()) - 1; }

  // Runs a program and waits for it to end.
  ur_emulator::ExecutedProgram Run(const std::string& body) {
    const size_t before = controller_->Snapshot().programs_finished;
    controller_->SubmitScript("def test():\n  set_tcp(p[0, 0, 0.1, 0, 0, 0])\n" + body + "end\n");
    EXPECT_TRUE(controller_->WaitFor(
        [&](const ur_emulator::RobotSnapshot& s) { return s.programs_finished > before; },
        absl::Seconds(60)));
    return controller_->Programs().back();
  }

  // Pick at `grasp` (world), lift, carry to `place` (world, box bottom +
  // height: the tcp) and release.
  std::string PickAndPlace(const Eigen::Vector3d& grasp, const Eigen::Vector3d& place) {
    return absl::StrFormat(
        "  movej(%s, a=1.4, v=1.05)\n  movel(%s, a=1, v=0.25)\n"
        "  set_tool_digital_out(0, True)\n  movel(%s, a=1, v=0.25)\n"
        "  movej(%s, a=1.4, v=1.05)\n  movel(%s, a=1, v=0.25)\n"
        "  set_tool_digital_out(0, False)\n  movel(%s, a=1, v=0.25)\n",
        DownAt(grasp, 0.1), DownAt(grasp), DownAt(grasp, 0.25), DownAt(place, 0.25), DownAt(place),
        DownAt(place, 0.25));
  }

  Eigen::Vector3d PlaceSpot() const {
    // Slot 0 of the place pattern, the tcp on the top face of the box put there.
    return cell_.layout.world_T_base * cell_.place_origin_base +
           Eigen::Vector3d(0, 0, cell_.boxes.front().dims.h);
  }

  SimCell cell_;
  std::shared_ptr<CellWorld> world_;
  std::unique_ptr<ur_emulator::Controller> controller_;
};

TEST_F(CellWorldTest, CapsulesFollowTheKinematics) {
  const ur::Joints q{0.3, -1.2, 1.4, -1.7, -1.5, 0.2};
  const Eigen::Isometry3d tcp(Eigen::Translation3d(0, 0, 0.1));
  const std::vector<Capsule> capsules = ArmCapsules(ur::ArmModel::kUr5e, q, tcp, ToolShape{});
  ASSERT_EQ(capsules.size(), 8u);
  const Eigen::Isometry3d flange = ur::ForwardKinematics(ur::ArmModel::kUr5e, q);
  EXPECT_LT((capsules[6].b - flange.translation()).norm(), 1e-9);  // wrist_3 ends at the flange
  // The tool stops the cup's compliance plus its radius short of the tip.
  EXPECT_NEAR(((flange * tcp).translation() - capsules[7].b).norm(), 0.01 + 0.03, 1e-9);
}

TEST_F(CellWorldTest, PicksTheBoxUnderTheCupAndSetsItDownOnTheSlot) {
  const int box = TopBox();
  const ur_emulator::ExecutedProgram program = Run(PickAndPlace(TopOf(box), PlaceSpot()));
  EXPECT_EQ(program.outcome, ur_emulator::ProgramOutcome::kCompleted) << program.error_text;
  const WorldSummary summary = world_->Summary();
  ASSERT_EQ(summary.picks.size(), 1u);
  EXPECT_EQ(summary.picks[0].result, PickResult::kPlaced) << summary.picks[0].detail;
  EXPECT_EQ(summary.picks[0].box_id, box);
  EXPECT_EQ(summary.collisions, 0);
  const SimBox placed = world_->Boxes()[static_cast<size_t>(box)];
  EXPECT_EQ(placed.state, BoxState::kPlaced);
  // It rests on the place pallet's deck, below where it was let go.
  EXPECT_NEAR(placed.world_T_box.translation().z(), testing::kEurPalletHeight + 0.5 * placed.dims.h,
              0.012);
  EXPECT_EQ(summary.placed, 1);
  EXPECT_GT(summary.picks[0].end_time_s - summary.picks[0].start_time_s, 1.0);
}

TEST_F(CellWorldTest, NothingUnderTheCupGripsNothing) {
  // 5 cm above a box's top face: the cup closes on air.
  const Eigen::Vector3d air = TopOf(TopBox()) + Eigen::Vector3d(0, 0.0, 0.05);
  const ur_emulator::ExecutedProgram program = Run(absl::StrFormat(
      "  movej(%s, a=1.4, v=1.05)\n  movel(%s, a=1, v=0.25)\n  set_tool_digital_out(0, True)\n"
      "  movel(%s, a=1, v=0.25)\n  set_tool_digital_out(0, False)\n",
      DownAt(air, 0.1), DownAt(air), DownAt(air, 0.2)));
  EXPECT_EQ(program.outcome, ur_emulator::ProgramOutcome::kCompleted);
  const WorldSummary summary = world_->Summary();
  ASSERT_EQ(summary.picks.size(), 1u);
  EXPECT_EQ(summary.picks[0].result, PickResult::kNothingGripped) << summary.picks[0].detail;
  EXPECT_EQ(summary.placed, 0);
  EXPECT_EQ(summary.in_pile, summary.boxes_total);
}

TEST_F(CellWorldTest, ACupOverTheEdgeLosesTheBoxOnTheWayUp) {
  const int box = TopBox();
  const SimBox b = world_->Boxes()[static_cast<size_t>(box)];
  // 1 cm inside the face's edge (the one towards the pallet's middle): the
  // 2 cm cup reaches over it.
  const double side = b.world_T_box.translation().x() > 0 ? -1.0 : 1.0;
  const Eigen::Vector3d near_edge =
      b.world_T_box * Eigen::Vector3d(side * (0.5 * b.dims.l - 0.01), 0, 0.5 * b.dims.h);
  const Eigen::Vector3d before = b.world_T_box.translation();
  const ur_emulator::ExecutedProgram program = Run(PickAndPlace(near_edge, PlaceSpot()));
  EXPECT_EQ(program.outcome, ur_emulator::ProgramOutcome::kCompleted) << program.error_text;
  const WorldSummary summary = world_->Summary();
  ASSERT_EQ(summary.picks.size(), 1u);
  EXPECT_EQ(summary.picks[0].result, PickResult::kDropped) << summary.picks[0].detail;
  const SimBox after = world_->Boxes()[static_cast<size_t>(box)];
  EXPECT_EQ(after.state, BoxState::kInPile);
  EXPECT_LT((after.world_T_box.translation() - before).norm(), 0.005);  // fell back in place
}

TEST_F(CellWorldTest, ABoxUnderAnotherCannotBeLifted) {
  // Box 0 is in the bottom layer, under a top-layer box, so no arm reaches
  // its top face: put the cup there directly through the world's interface.
  const SimBox bottom = world_->Boxes()[0];
  Eigen::Isometry3d tcp = Eigen::Isometry3d::Identity();
  tcp.linear() << 1, 0, 0, 0, -1, 0, 0, 0, -1;
  tcp.translation() = bottom.world_T_box * Eigen::Vector3d(0, 0, 0.5 * bottom.dims.h);
  ur_emulator::ArmState state;
  state.base_T_tcp = cell_.layout.world_T_base.inverse() * tcp;
  state.program = "direct";
  world_->OnProgramStart("direct", 0.0);
  state.tool_outputs = 1;
  world_->OnOutputs(state);
  world_->OnProgramEnd("direct", true, 1.0);
  const WorldSummary summary = world_->Summary();
  ASSERT_EQ(summary.picks.size(), 1u);
  EXPECT_EQ(summary.picks[0].result, PickResult::kNothingGripped);
  EXPECT_NE(summary.picks[0].detail.find("lies on it"), std::string::npos)
      << summary.picks[0].detail;
  EXPECT_EQ(summary.held, 0);
}

TEST_F(CellWorldTest, LoweringTheHeldBoxIntoThePileIsACollision) {
  const int box = TopBox();
  const Eigen::Vector3d grasp = TopOf(box);
  // Pick it, then push it down 5 cm into its neighbour's place.
  const Eigen::Vector3d neighbour = TopOf(box - 1);
  const ur_emulator::ExecutedProgram program = Run(absl::StrFormat(
      "  movej(%s, a=1.4, v=1.05)\n  movel(%s, a=1, v=0.25)\n  set_tool_digital_out(0, True)\n"
      "  movel(%s, a=1, v=0.25)\n  movel(%s, a=1, v=0.25)\n  movel(%s, a=1, v=0.25)\n",
      DownAt(grasp, 0.1), DownAt(grasp), DownAt(grasp, 0.25), DownAt(neighbour, 0.25),
      DownAt(neighbour, -0.05)));
  EXPECT_EQ(program.outcome, ur_emulator::ProgramOutcome::kProtectiveStop);
  EXPECT_EQ(controller_->Snapshot().safety_mode, ur_emulator::kSafetyModeProtectiveStop);
  const WorldSummary summary = world_->Summary();
  EXPECT_EQ(summary.collisions, 1);
  ASSERT_EQ(summary.picks.size(), 1u);
  EXPECT_EQ(summary.picks[0].result, PickResult::kCollision);
  EXPECT_NE(summary.picks[0].detail.find("the held box"), std::string::npos)
      << summary.picks[0].detail;
}

TEST_F(CellWorldTest, TheCameraShowsThePickedBoxGone) {
  const std::string dir = ::testing::TempDir() + "/cell_world_camera";
  SimCameraOptions options;
  options.directory = dir;
  options.sensor = "ideal";
  absl::StatusOr<std::unique_ptr<SimCamera>> camera = SimCamera::Start(world_.get(), options);
  ASSERT_TRUE(camera.ok()) << camera.status();
  const int box = TopBox();
  // The pixel over the box's top centre.
  const Eigen::Vector3d top = TopOf(box);
  const Eigen::Vector3d in_camera = cell_.layout.world_T_camera.inverse() * top;
  const CameraIntrinsics& cam = cell_.layout.camera;
  const int u = static_cast<int>(std::lround(cam.fx * in_camera.x() / in_camera.z() + cam.cx));
  const int v = static_cast<int>(std::lround(cam.fy * in_camera.y() / in_camera.z() + cam.cy));
  auto depth_at = [&]() {
    std::string newest;
    for (const auto& e : std::filesystem::directory_iterator(dir)) {
      if (e.path().extension() == ".png" && e.path().string() > newest) newest = e.path().string();
    }
    int w = 0, h = 0;
    absl::StatusOr<std::vector<uint16_t>> depth = ReadDepthPng(newest, &w, &h);
    EXPECT_TRUE(depth.ok()) << depth.status();
    return depth.ok() ? static_cast<int>((*depth)[static_cast<size_t>(v * w + u)]) : -1;
  };
  const int before_mm = depth_at();
  EXPECT_NEAR(before_mm, 1000 * in_camera.z(), 3);
  Run(PickAndPlace(top, PlaceSpot()));
  // The program's end waited for the camera: the newest frame already shows
  // the layer below (one box height further away).
  EXPECT_NEAR(depth_at() - before_mm, 1000 * cell_.boxes.front().dims.h, 5);
}

TEST(SimCellTest, RejectsBadOptions) {
  SimLoadOptions load;
  load.kind = "crate";
  EXPECT_EQ(MakeSimCell({}, load).status().code(), absl::StatusCode::kInvalidArgument);
  load = {};
  load.layers = 0;
  EXPECT_NE(MakeSimCell({}, load).status().message().find("layers"), std::string::npos);
  SimCellOptions cell;
  cell.camera_height_m = 9;
  EXPECT_NE(MakeSimCell(cell, {}).status().message().find("camera_height_m"), std::string::npos);
}

TEST(SimCellTest, APalletOfCartonsHasThreeLayersOfTwelve) {
  absl::StatusOr<SimCell> cell = MakeSimCell({}, {});
  ASSERT_TRUE(cell.ok()) << cell.status();
  EXPECT_EQ(cell->boxes.size(), 36u);
  EXPECT_GE(cell->place_rows * cell->place_columns * cell->place_layers, 36);
  SimLoadOptions interlock;
  interlock.pattern = "interlock";
  EXPECT_EQ(MakeSimCell({}, interlock)->boxes.size(), 36u);
  SimLoadOptions bin;
  bin.kind = "bin";
  bin.heap_boxes = 6;
  absl::StatusOr<SimCell> binned = MakeSimCell({}, bin);
  ASSERT_TRUE(binned.ok()) << binned.status();
  EXPECT_EQ(binned->boxes.size(), 6u);
}

}  // namespace
}  // namespace cornerpose::cell_sim
