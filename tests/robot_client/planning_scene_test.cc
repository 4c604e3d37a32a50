// The free moves' contact check (planning_scene.h) and the transit it
// makes PlanPick take: the scene built from detected boxes and filled
// slots, the joint-space sweep finding the link or the held box that comes
// too close, what the arm stands in dropped, and the demo cell's pick that
// hit its neighbour (a top-layer carton carried to the empty place pallet)
// planned through a transit above the slot.
#include "robot_client/planning/planning_scene.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <vector>

#include "robot_client/config/robot_config.h"
#include "robot_client/planning/pick_plan.h"
#include "robot_client/planning/place_pattern.h"
#include "robot_client/ur/kinematics.h"

namespace cornerpose::robot_client {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;

const BoxDims kCarton{0.30, 0.20, 0.15};

// The simulated cell as the daemon is configured for it
// (deploy/config/sim_robot_client.textproto): a UR5e between a pick pallet
// at +y and a place pallet at -y, the place pattern, the workspace and the
// clear pose.
const RobotClientOptions& SimCell() {
  static const RobotClientOptions options = [] {
    absl::StatusOr<RobotClientOptions> loaded = LoadRobotClientConfig(
        (std::filesystem::path(CORNERPOSE_SOURCE_DIR) / "deploy/config/sim_robot_client.textproto")
            .string());
    EXPECT_TRUE(loaded.ok()) << loaded.status();
    return loaded.ok() ? *loaded : RobotClientOptions{};
  }();
  return options;
}
const ur::Joints& Clear() { return *SimCell().clear_joints; }
double Floor() { return SimCell().workspace.min_m.z(); }
ur::ArmModel Arm() { return SimCell().robot.arm_model; }
const Eigen::Isometry3d& Tcp() { return SimCell().gripper.flange_T_tcp; }

BoxInBase Carton(double x, double y, double top_z) {
  DetectedBox box;
  box.camera_T_box.translation() = Eigen::Vector3d(x, y, top_z - 0.075);
  box.grasp_face = BoxFace::kPlusZ;
  return BoxToBase(box, Eigen::Isometry3d::Identity(), kCarton);
}

// The top layer of the demo's pallet: 4 x 3 cartons, tops at z = -0.056.
std::vector<BoxInBase> TopLayer() {
  std::vector<BoxInBase> boxes;
  for (double y : {0.288, 0.490, 0.692}) {
    for (double x : {-0.454, -0.152, 0.150, 0.454}) boxes.push_back(Carton(x, y, -0.056));
  }
  for (BoxInBase& b : boxes) b.pile_top_z_m = -0.056;
  return boxes;
}

TEST(PlanningSceneTest, ColumnsUnderDetectedBoxesAndBlocksOnFilledSlots) {
  const std::vector<BoxInBase> boxes = {Carton(0.1, 0.5, 0.2), Carton(-0.3, 0.5, 0.05)};
  const PlanningScene scene = ScenePerPick(boxes, kCarton, SimCell().place_pattern, 5, Floor());
  ASSERT_EQ(scene.obstacles.size(), 2u + 5u);
  // A column from the floor to the box's top over its footprint.
  const collision::Aabb column = collision::BoundsOf(scene.obstacles[0].box);
  EXPECT_NEAR(column.min.z(), Floor(), 1e-9);
  EXPECT_NEAR(column.max.z(), 0.2, 1e-9);
  EXPECT_NEAR(column.max.x() - column.min.x(), 0.30, 1e-9);
  EXPECT_NEAR(column.max.y() - column.min.y(), 0.20, 1e-9);
  EXPECT_THAT(scene.obstacles[0].name, HasSubstr("detected box 0"));
  // Slot 4's cell: its pattern position, one layer tall, 5 mm in from the
  // cell's sides.
  const collision::Aabb cell = collision::BoundsOf(scene.obstacles[2 + 4].box);
  const Eigen::Vector3d slot4 = SlotPose(SimCell().place_pattern, 4)->translation();
  EXPECT_NEAR(0.5 * (cell.min.x() + cell.max.x()), slot4.x(), 1e-9);
  EXPECT_NEAR(cell.min.z(), slot4.z(), 1e-9);
  EXPECT_NEAR(cell.max.x() - cell.min.x(), SimCell().place_pattern.spacing_x_m - 0.01, 1e-9);
  EXPECT_THAT(scene.obstacles[2 + 4].name, HasSubstr("slot 4"));
  // No slot filled, no box seen: nothing.
  EXPECT_TRUE(ScenePerPick({}, kCarton, SimCell().place_pattern, 0, Floor()).obstacles.empty());
}

TEST(PlanningSceneTest, AFreeMoveThroughABoxNamesTheLinkAndTheBox) {
  // The tool swept from above the pallet's left to its right, 5 cm above
  // the tops, then through a box standing 0.3 m higher in between.
  const Eigen::Isometry3d down(Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX()));
  auto joints_at = [&](double x) {
    Eigen::Isometry3d tcp = down;
    tcp.translation() = Eigen::Vector3d(x, 0.49, -0.006);
    return *ur::InverseKinematics(Arm(), tcp * Tcp().inverse(), Clear());
  };
  const ur::Joints from = joints_at(-0.3), to = joints_at(0.3);
  PlanningScene scene = ScenePerPick(TopLayer(), kCarton, SimCell().place_pattern, 0, Floor());
  EXPECT_TRUE(
      CheckFreeMove(Arm(), Tcp(), from, to, std::nullopt, scene, CollisionCheckOptions{}, "test")
          .ok());
  collision::Obb tall;
  tall.dims = BoxDims{0.2, 0.2, 0.3};
  tall.world_T_box.translation() = Eigen::Vector3d(0.0, 0.49, 0.0);
  scene.obstacles.push_back({"the tall box", tall});
  const absl::Status hit =
      CheckFreeMove(Arm(), Tcp(), from, to, std::nullopt, scene, CollisionCheckOptions{}, "test");
  EXPECT_EQ(hit.code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_THAT(hit.message(), HasSubstr("free move test: the "));
  EXPECT_THAT(hit.message(), HasSubstr(" comes within 0.020 m of the tall box at ("));
  // A held box 0.15 m deep under the cup hits the top layer on the same move.
  const HeldBox held{kCarton, Eigen::Isometry3d(Eigen::Translation3d(0, 0, 0.075))};
  scene.obstacles.pop_back();
  const absl::Status carried =
      CheckFreeMove(Arm(), Tcp(), from, to, held, scene, CollisionCheckOptions{}, "R->place_above");
  EXPECT_THAT(carried.message(), HasSubstr("the held box comes within 0.020 m of detected box"));
}

TEST(PlanningSceneTest, WhatTheArmStandsInIsDropped) {
  // A box-shaped pedestal top seen under the robot's base is the robot's.
  std::vector<BoxInBase> boxes = TopLayer();
  boxes.push_back(Carton(0.0, 0.0, 0.0));
  PlanningScene scene = ScenePerPick(boxes, kCarton, SimCell().place_pattern, 0, Floor());
  ASSERT_EQ(scene.obstacles.size(), 13u);
  DropWhatTheArmOccupies(Arm(), Tcp(), Clear(), CollisionCheckOptions{}, scene);
  ASSERT_EQ(scene.obstacles.size(), 12u);
  for (const SceneObstacle& o : scene.obstacles) EXPECT_THAT(o.name, Not(HasSubstr("box 12")));
}

TEST(PlanningSceneTest, ALowPlaceIsReachedThroughATransitClearOfThePile) {
  // The demo's 8th pick: the top layer's far-left middle carton to slot 7,
  // on the empty place pallet's first layer. The direct movej from R sinks
  // the held box into its neighbour on the way out.
  const CollisionCheckOptions checks;
  std::vector<BoxInBase> layer = TopLayer();
  const BoxInBase picked = layer[4];  // (-0.454, 0.490)
  const PlanningScene scene = ScenePerPick(layer, kCarton, SimCell().place_pattern, 7, Floor());

  absl::StatusOr<PickPlan> unchecked = PlanPickForSlot(SimCell(), Clear(), picked, 7, kCarton);
  ASSERT_TRUE(unchecked.ok()) << unchecked.status();
  EXPECT_FALSE(unchecked->transit.has_value());
  const HeldBox held{kCarton, unchecked->tcp_T_box};
  const absl::Status direct =
      CheckFreeMove(Arm(), Tcp(), unchecked->retrieve_joints, unchecked->place_above_joints, held,
                    scene, checks, "R->place_above");
  EXPECT_EQ(direct.code(), absl::StatusCode::kFailedPrecondition) << "the direct move was clear";

  absl::StatusOr<PickPlan> plan = PlanPickForSlot(SimCell(), Clear(), picked, 7, kCarton, &scene);
  ASSERT_TRUE(plan.ok()) << plan.status();
  ASSERT_TRUE(plan->transit.has_value());
  // Above the slot, at R's height or higher.
  EXPECT_NEAR(plan->transit->translation().x(), plan->place_above.translation().x(), 1e-9);
  EXPECT_NEAR(plan->transit->translation().y(), plan->place_above.translation().y(), 1e-9);
  EXPECT_GE(plan->transit->translation().z(), plan->retrieve.translation().z() - 1e-9);
  for (const auto& [from, to] : {std::pair{plan->retrieve_joints, plan->transit_joints},
                                 std::pair{plan->transit_joints, plan->place_above_joints}}) {
    EXPECT_TRUE(CheckFreeMove(Arm(), Tcp(), from, to, HeldBox{kCarton, plan->tcp_T_box}, scene,
                              checks, "leg")
                    .ok());
  }
  // The approach from the clear pose is clear too.
  EXPECT_TRUE(CheckFreeMove(Arm(), Tcp(), plan->initial_joints, plan->approach_joints, std::nullopt,
                            scene, checks, "I->M")
                  .ok());
}

TEST(PlanningSceneTest, OptionsOutOfRangeNameTheField) {
  CollisionCheckOptions o;
  EXPECT_TRUE(o.Validate().ok());
  o.clearance_m = -0.1;
  EXPECT_THAT(o.Validate().message(), HasSubstr("clearance_m"));
  o = {};
  o.max_step_rad = 0.0;
  EXPECT_THAT(o.Validate().message(), HasSubstr("max_step_rad"));
  o = {};
  o.tool.radius_m = 0.0;
  EXPECT_THAT(o.Validate().message(), HasSubstr("tool.radius_m"));
}

}  // namespace
}  // namespace cornerpose::robot_client
