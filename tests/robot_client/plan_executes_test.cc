// The programs of planned picks run to the end on the UR controller
// emulator (tests/support/ur_emulator), which follows every movel step by
// step and stops a move whose joints jump (a singularity or an IK branch
// flip) as a real controller would: for cartons all over the demo cell's
// pick area, one pick after the other from the emulator's start-up joints,
// each program PlanPickForSlot returns completes. The demo's singular
// retrieve, which the planner refuses, fails there.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/time/time.h"
#include "robot_client/config/robot_config.h"
#include "robot_client/planning/grasp_geometry.h"
#include "robot_client/planning/pick_plan.h"
#include "robot_client/planning/place_pattern.h"
#include "robot_client/planning/urscript_program.h"
#include "robot_client/ur/pose.h"
#include "tests/robot_client/test_config.h"
#include "tests/robot_client/test_poses.h"
#include "tests/support/ur_emulator/controller.h"

namespace cornerpose::robot_client {
namespace {

using testing::ToolDownAt;

// Simulated seconds per wall second: a pick takes about 15 simulated s.
constexpr double kTimeScale = 200.0;
const absl::Duration kProgramTimeout = absl::Seconds(60);

class PlanExecutesTest : public ::testing::Test {
 protected:
  void SetUp() override {
    absl::StatusOr<RobotClientOptions> options =
        LoadRobotClientConfig(testing::ShippedConfigPath());
    ASSERT_TRUE(options.ok()) << options.status();
    options_ = *options;
    ur_emulator::UrEmulatorOptions emulator;
    emulator.model = options_.robot.arm_model;
    emulator.time_scale = kTimeScale;
    controller_ = std::make_unique<ur_emulator::Controller>(emulator);
    ASSERT_TRUE(controller_->PowerOn());
    ASSERT_TRUE(controller_->WaitFor(
        [](const ur_emulator::RobotSnapshot& s) {
          return s.robot_mode == ur_emulator::kRobotModeIdle;
        },
        absl::Seconds(30)));
    ASSERT_TRUE(controller_->BrakeRelease());
    ASSERT_TRUE(controller_->WaitFor(
        [](const ur_emulator::RobotSnapshot& s) {
          return s.robot_mode == ur_emulator::kRobotModeRunning;
        },
        absl::Seconds(30)));
  }

  // Submits `text` and waits for it to end; the recorded program.
  ur_emulator::ExecutedProgram Run(const std::string& text) {
    const size_t finished = controller_->Snapshot().programs_finished;
    controller_->SubmitScript(text);
    EXPECT_TRUE(controller_->WaitFor(
        [finished](const ur_emulator::RobotSnapshot& s) { return s.programs_finished > finished; },
        kProgramTimeout))
        << "program did not end";
    const std::vector<ur_emulator::ExecutedProgram> programs = controller_->Programs();
    if (programs.empty()) return {};
    return programs.back();
  }

  RobotClientOptions options_;
  std::unique_ptr<ur_emulator::Controller> controller_;
};

TEST_F(PlanExecutesTest, TheDemosSingularRetrieveFailsOnTheEmulator) {
  const std::string text = absl::StrCat(
      "def singular():\n  set_tcp(",
      ur::FormatPoseLiteral(ur::ToUrPose(options_.gripper.flange_T_tcp)), ")\n  movej(",
      ur::FormatPoseLiteral(ur::ToUrPose(ToolDownAt(0.0, -0.322, 0.450, 0.0))),
      ", a=1.4, v=1.05)\n  movel(",
      ur::FormatPoseLiteral(ur::ToUrPose(ToolDownAt(0.0, -0.322, 0.680, 0.0))),
      ", a=0.5, v=0.1)\nend\n");
  const ur_emulator::ExecutedProgram program = Run(text);
  EXPECT_EQ(program.outcome, ur_emulator::ProgramOutcome::kRuntimeException)
      << ur_emulator::ProgramOutcomeName(program.outcome);
  EXPECT_THAT(program.error_text, ::testing::HasSubstr("runtime_error_movel_joint_jump"));
}

TEST_F(PlanExecutesTest, EveryPlannedPickRunsToTheEnd) {
  const Eigen::Vector3d centre = options_.base_T_camera.translation();
  int picks = 0, refused = 0;
  for (double dx : {-0.3, 0.0, 0.3}) {
    for (double dy : {-0.25, 0.0, 0.25}) {
      for (double top : {0.15, 0.30, 0.45}) {
        for (double yaw : {0.0, 1.6}) {
          Eigen::Isometry3d base_T_box = Eigen::Isometry3d::Identity();
          base_T_box.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
          base_T_box.translation() = Eigen::Vector3d(centre.x() + dx, centre.y() + dy,
                                                     top - 0.5 * options_.perception.box.h);
          DetectedBox carton;
          carton.camera_T_box = options_.base_T_camera.inverse() * base_T_box;
          carton.grasp_face = BoxFace::kPlusZ;
          const BoxInBase box = BoxToBase(carton, options_.base_T_camera, options_.perception.box);
          const int slot = (picks + refused) % SlotCount(options_.place_pattern);
          // Planned from where the arm is, as the daemon does.
          const ur::Joints joints = controller_->Snapshot().joints;
          absl::StatusOr<PickPlan> plan = PlanPickForSlot(options_, joints, box, slot);
          if (!plan.ok()) {
            ++refused;
            continue;
          }
          SCOPED_TRACE(::testing::Message() << "box at " << box.grasp_point.transpose() << " yaw "
                                            << yaw << " slot " << slot);
          absl::StatusOr<std::string> text =
              RenderPickProgram(PickProgramName(picks), *plan, options_.gripper, options_.motion,
                                *options_.clear_joints);
          ASSERT_TRUE(text.ok()) << text.status();
          const ur_emulator::ExecutedProgram program = Run(*text);
          ASSERT_EQ(program.outcome, ur_emulator::ProgramOutcome::kCompleted)
              << ur_emulator::ProgramOutcomeName(program.outcome) << ": " << program.error_text
              << " at line " << program.error_line;
          ++picks;
        }
      }
    }
  }
  std::cerr << picks << " picks ran, " << refused << " refused by the planner\n";
  EXPECT_GT(picks, refused);
}

}  // namespace
}  // namespace cornerpose::robot_client
