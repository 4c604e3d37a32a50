// The waypoint geometry: BoxToBase, the four grasps, and PlanPick's M, G, R,
// place_above and F (distances, directions, tool axes, the least wrist
// rotation, the box's bottom on the slot), with workspace and reachability
// refusals naming the waypoint; CheckStraightMove, and PlanPick skipping
// orientations whose straight moves pass a singularity.
#include "robot_client/planning/pick_plan.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "robot_client/planning/grasp_geometry.h"
#include "robot_client/planning/straight_move.h"
#include "robot_client/ur/kinematics.h"
#include "robot_client/ur/pose.h"
#include "tests/robot_client/test_poses.h"

namespace cornerpose::robot_client {
namespace {

using ::testing::AnyOf;
using ::testing::HasSubstr;

constexpr double kTol = 1e-9;
const BoxDims kCarton{0.30, 0.20, 0.15};

Eigen::Isometry3d Pose(const Eigen::Vector3d& p, const Eigen::Matrix3d& R) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = R;
  T.translation() = p;
  return T;
}

Eigen::Matrix3d Rot(double angle, const Eigen::Vector3d& axis) {
  return Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
}

// A tool pointing down (tool z = base -z) turned by `yaw` about base z.
Eigen::Isometry3d ToolDown(const Eigen::Vector3d& p, double yaw) {
  return Pose(p, Rot(yaw, Eigen::Vector3d::UnitZ()) * Rot(M_PI, Eigen::Vector3d::UnitX()));
}

// A carton lying flat (grasp face +z up), centroid at `centre`, yawed.
DetectedBox FlatBox(const Eigen::Vector3d& centre, double yaw, double score = 0.9) {
  DetectedBox box;
  box.camera_T_box = Pose(centre, Rot(yaw, Eigen::Vector3d::UnitZ()));
  box.grasp_face = BoxFace::kPlusZ;
  box.score = score;
  return box;
}

// The UR controller emulator's start-up joints (tool pointing down).
constexpr ur::Joints kHome = testing::kEmulatorHomeJoints;

// A UR5e with the suction cup 0.10 m out along the flange's z axis, its
// joints putting the TCP at `tcp` (the IK solution nearest kHome).
PickArm ArmAt(const Eigen::Isometry3d& tcp) {
  PickArm arm;
  arm.model = ur::ArmModel::kUr5e;
  arm.flange_T_tcp.translation() = Eigen::Vector3d(0, 0, 0.10);
  absl::StatusOr<ur::Joints> q =
      ur::InverseKinematics(arm.model, tcp * arm.flange_T_tcp.inverse(), kHome);
  EXPECT_TRUE(q.ok()) << q.status();
  if (q.ok()) arm.joints = *q;
  return arm;
}

Workspace BigWorkspace() {
  Workspace w;
  w.min_m = Eigen::Vector3d(-2, -2, -0.5);
  w.max_m = Eigen::Vector3d(2, 2, 2);
  return w;
}

TEST(GraspGeometryTest, BoxToBaseGivesTheFaceCentreNormalAndTilt) {
  const Eigen::Isometry3d base_T_camera =
      Pose(Eigen::Vector3d(0, -0.5, 1.1), Rot(M_PI, Eigen::Vector3d::UnitX()));
  DetectedBox box = FlatBox(Eigen::Vector3d(0.1, -0.4, 0.075), 0.3);
  box.camera_T_box = base_T_camera.inverse() * box.camera_T_box;  // as the camera sees it
  const BoxInBase in_base = BoxToBase(box, base_T_camera, kCarton);
  EXPECT_TRUE(in_base.grasp_point.isApprox(Eigen::Vector3d(0.1, -0.4, 0.15), kTol));
  EXPECT_TRUE(in_base.grasp_normal.isApprox(Eigen::Vector3d::UnitZ(), kTol));
  EXPECT_DOUBLE_EQ(in_base.depth_m, 0.15);
  EXPECT_NEAR(in_base.tilt_deg, 0.0, 1e-6);

  DetectedBox tilted = FlatBox(Eigen::Vector3d(0, 0, 0), 0.0);
  tilted.camera_T_box.linear() = Rot(20.0 * M_PI / 180.0, Eigen::Vector3d::UnitX());
  tilted.grasp_face = BoxFace::kPlusY;  // depth along y: b
  const BoxInBase t = BoxToBase(tilted, Eigen::Isometry3d::Identity(), kCarton);
  EXPECT_DOUBLE_EQ(t.depth_m, 0.20);
  EXPECT_NEAR(t.tilt_deg, 70.0, 1e-6);
  EXPECT_NEAR((t.grasp_point - Eigen::Vector3d::Zero()).norm(), 0.10, kTol);
}

TEST(GraspGeometryTest, FourGraspsPointIntoTheFaceSortedByRotation) {
  DetectedBox box = FlatBox(Eigen::Vector3d(0.2, -0.5, 0.075), 0.4);
  // Tilt it so the face normal is not vertical: the tool must follow it.
  box.camera_T_box.linear() = Rot(0.3, Eigen::Vector3d(1, 1, 0)) * box.camera_T_box.linear();
  const BoxInBase b = BoxToBase(box, Eigen::Isometry3d::Identity(), kCarton);
  const Eigen::Quaterniond now(ToolDown(Eigen::Vector3d::Zero(), 2.0).linear());
  const std::array<Eigen::Isometry3d, 4> grasps = GraspCandidates(b, now);
  double last = -1.0;
  for (const Eigen::Isometry3d& g : grasps) {
    EXPECT_TRUE(g.translation().isApprox(b.grasp_point, kTol));
    EXPECT_TRUE(g.linear().col(2).isApprox(-b.grasp_normal, kTol));
    EXPECT_NEAR(g.linear().determinant(), 1.0, kTol);
    // Tool x lies along one of the box's in-face axes (x or y for +z).
    const Eigen::Vector3d x = g.linear().col(0);
    const double along = std::max(std::abs(x.dot(b.base_T_box.linear().col(0))),
                                  std::abs(x.dot(b.base_T_box.linear().col(1))));
    EXPECT_NEAR(along, 1.0, kTol);
    const double angle = ur::RotationAngleBetween(now, Eigen::Quaterniond(g.linear()));
    EXPECT_GE(angle, last);
    last = angle;
  }
  // The four differ by quarter turns about the tool axis.
  for (int i = 1; i < 4; ++i) {
    EXPECT_NEAR(std::abs(grasps[0].linear().col(0).dot(grasps[i].linear().col(0))) +
                    std::abs(grasps[0].linear().col(0).dot(grasps[i].linear().col(1))),
                1.0, kTol);
  }
}

class PickPlanTest : public ::testing::Test {
 protected:
  WaypointOptions waypoints_;  // d 0.10, h 0.25, place above 0.10
  Workspace workspace_ = BigWorkspace();
  Eigen::Isometry3d slot_ =
      Pose(Eigen::Vector3d(-0.3, 0.4, 0.0), Rot(0.5, Eigen::Vector3d::UnitZ()));
};

TEST_F(PickPlanTest, WaypointsFollowThePaper) {
  const BoxInBase box = BoxToBase(FlatBox(Eigen::Vector3d(0.1, -0.5, 0.075), 0.7),
                                  Eigen::Isometry3d::Identity(), kCarton);
  const Eigen::Isometry3d now = ToolDown(Eigen::Vector3d(0, 0.3, 0.5), 0.0);
  absl::StatusOr<PickPlan> plan =
      PlanPick(ArmAt(now), box, kCarton, slot_, 3, waypoints_, workspace_);
  ASSERT_TRUE(plan.ok()) << plan.status();
  EXPECT_EQ(plan->slot, 3);
  EXPECT_TRUE(plan->initial.isApprox(now, 1e-6));
  EXPECT_TRUE(plan->grasp.translation().isApprox(Eigen::Vector3d(0.1, -0.5, 0.15), kTol));
  // M = G + d z, R = G + h z, same orientation as G.
  EXPECT_TRUE((plan->approach.translation() - plan->grasp.translation())
                  .isApprox(Eigen::Vector3d(0, 0, 0.10), kTol));
  EXPECT_TRUE((plan->retrieve.translation() - plan->grasp.translation())
                  .isApprox(Eigen::Vector3d(0, 0, 0.25), kTol));
  EXPECT_TRUE(plan->approach.linear().isApprox(plan->grasp.linear(), kTol));
  EXPECT_TRUE(plan->retrieve.linear().isApprox(plan->grasp.linear(), kTol));
  // Tool z antiparallel to the face's outward normal.
  EXPECT_NEAR(plan->grasp.linear().col(2).dot(box.grasp_normal), -1.0, kTol);
  // place_above = F + a z, a = 0.15 (the carton's height) + 5 cm clearance
  // over the boxes already in its layer.
  EXPECT_TRUE((plan->place_above.translation() - plan->place.translation())
                  .isApprox(Eigen::Vector3d(0, 0, 0.20), kTol));
  EXPECT_TRUE(plan->place_above.linear().isApprox(plan->place.linear(), kTol));
  // The held box goes with the tool, and its bottom centre lands on the slot.
  EXPECT_TRUE((plan->place * plan->tcp_T_box).isApprox(plan->base_T_box_placed, kTol));
  EXPECT_TRUE((plan->grasp * plan->tcp_T_box).isApprox(box.base_T_box, kTol));
  const Eigen::Vector3d bottom = plan->base_T_box_placed * Eigen::Vector3d(0, 0, -0.075);
  EXPECT_TRUE(bottom.isApprox(slot_.translation(), kTol)) << bottom.transpose();
  // Grasped face up, the longer side (l, box x) along the slot's x.
  EXPECT_TRUE(plan->base_T_box_placed.linear().col(2).isApprox(slot_.linear().col(2), kTol));
  EXPECT_NEAR(std::abs(plan->base_T_box_placed.linear().col(0).dot(slot_.linear().col(0))), 1.0,
              kTol);
  // F is 0.15 (the box height) above the slot, tool pointing down.
  EXPECT_TRUE(plan->place.translation().isApprox(Eigen::Vector3d(-0.3, 0.4, 0.15), kTol));
  EXPECT_TRUE(plan->place.linear().col(2).isApprox(-Eigen::Vector3d::UnitZ(), kTol));
  // Of the two box orientations on the slot, the one nearer G's tool.
  EXPECT_LE(plan->place_rotation_rad, M_PI / 2 + 1e-9);
}

TEST_F(PickPlanTest, ChoosesTheGraspWithTheLeastWristRotation) {
  const BoxInBase box = BoxToBase(FlatBox(Eigen::Vector3d(0.1, -0.5, 0.075), 0.2),
                                  Eigen::Isometry3d::Identity(), kCarton);
  for (double yaw : {0.0, 0.5, 1.2, 2.0, 2.9, -1.0, -2.5}) {
    SCOPED_TRACE(yaw);
    const Eigen::Isometry3d now = ToolDown(Eigen::Vector3d(0, 0.3, 0.5), yaw);
    absl::StatusOr<PickPlan> plan =
        PlanPick(ArmAt(now), box, kCarton, slot_, 0, waypoints_, workspace_);
    ASSERT_TRUE(plan.ok()) << plan.status();
    // Quarter-turn symmetry: never more than 45 degrees of wrist rotation.
    EXPECT_LE(plan->grasp_rotation_rad, M_PI / 4 + 1e-9);
    double best = 10.0;
    for (const Eigen::Isometry3d& g : GraspCandidates(box, Eigen::Quaterniond(now.linear()))) {
      best = std::min(best, ur::RotationAngleBetween(Eigen::Quaterniond(now.linear()),
                                                     Eigen::Quaterniond(g.linear())));
    }
    EXPECT_NEAR(plan->grasp_rotation_rad, best, 1e-12);
    // The tool turns about its own axis only: the grasp's yaw is the box's
    // yaw (0.2) plus a quarter-turn multiple, within 45 degrees of `yaw`.
    const double grasp_yaw = std::atan2(plan->grasp.linear()(1, 0), plan->grasp.linear()(0, 0));
    const double quarter = std::remainder(grasp_yaw - 0.2, M_PI / 2);
    EXPECT_NEAR(quarter, 0.0, 1e-9);
    EXPECT_LE(std::abs(std::remainder(grasp_yaw - yaw, 2 * M_PI)), M_PI / 4 + 1e-9);
  }
}

TEST_F(PickPlanTest, BoxOnItsSideIsPlacedGraspedFaceUpOnTheSlot) {
  // Standing on a long side: box y points up, so the detector grasps +y.
  DetectedBox standing;
  standing.camera_T_box =
      Pose(Eigen::Vector3d(0.0, -0.6, 0.10), Rot(M_PI / 2, Eigen::Vector3d::UnitX()));
  standing.grasp_face = BoxFace::kPlusY;
  const BoxInBase box = BoxToBase(standing, Eigen::Isometry3d::Identity(), kCarton);
  ASSERT_TRUE(box.grasp_normal.isApprox(Eigen::Vector3d::UnitZ(), kTol));
  absl::StatusOr<PickPlan> plan = PlanPick(ArmAt(ToolDown(Eigen::Vector3d(0, 0.3, 0.5), 0.0)), box,
                                           kCarton, slot_, 0, waypoints_, workspace_);
  ASSERT_TRUE(plan.ok()) << plan.status();
  EXPECT_TRUE(plan->grasp.translation().isApprox(Eigen::Vector3d(0.0, -0.6, 0.20), kTol));
  const Eigen::Matrix3d& placed = plan->base_T_box_placed.linear();
  EXPECT_TRUE(placed.col(1).isApprox(slot_.linear().col(2), kTol));            // +y face up
  EXPECT_NEAR(std::abs(placed.col(0).dot(slot_.linear().col(0))), 1.0, kTol);  // l along x
  const Eigen::Vector3d bottom = plan->base_T_box_placed * Eigen::Vector3d(0, -0.10, 0);
  EXPECT_TRUE(bottom.isApprox(slot_.translation(), kTol));
  EXPECT_TRUE(
      plan->place.translation().isApprox(slot_.translation() + Eigen::Vector3d(0, 0, 0.2), kTol));
}

TEST_F(PickPlanTest, WaypointOutsideTheWorkspaceIsRefusedByName) {
  const BoxInBase box = BoxToBase(FlatBox(Eigen::Vector3d(0.1, -0.5, 0.075), 0.0),
                                  Eigen::Isometry3d::Identity(), kCarton);
  Workspace low = workspace_;
  low.max_m.z() = 0.35;  // G 0.15 and M 0.25 inside, R 0.40 not
  absl::StatusOr<PickPlan> plan = PlanPick(ArmAt(ToolDown(Eigen::Vector3d(0, 0.3, 0.3), 0)), box,
                                           kCarton, slot_, 0, waypoints_, low);
  ASSERT_EQ(plan.status().code(), absl::StatusCode::kFailedPrecondition) << plan.status();
  EXPECT_THAT(plan.status().message(), HasSubstr("R (retrieve)"));
  EXPECT_THAT(plan.status().message(), HasSubstr("outside the workspace"));

  Workspace no_place = workspace_;
  no_place.min_m.y() = -1.0;
  no_place.max_m.y() = 0.0;  // the slot at y 0.4 is outside
  plan = PlanPick(ArmAt(ToolDown(Eigen::Vector3d(0, -0.3, 0.5), 0)), box, kCarton, slot_, 0,
                  waypoints_, no_place);
  ASSERT_EQ(plan.status().code(), absl::StatusCode::kFailedPrecondition) << plan.status();
  EXPECT_THAT(plan.status().message(), HasSubstr("place_above"));
}

TEST(StraightMoveTest, OrdinaryRetrieveAndTurnPass) {
  // Straight up 0.25 m from a carton top on the table in front of the robot.
  const Eigen::Isometry3d g = ToolDown(Eigen::Vector3d(0.1, -0.5, 0.15), 0.3);
  const Eigen::Isometry3d r = RaisedAlongBaseZ(g, 0.25);
  const PickArm arm = ArmAt(g);
  ur::Joints end{};
  ASSERT_TRUE(
      CheckStraightMove(arm.model, arm.flange_T_tcp, arm.joints, g, r, StraightMoveOptions(), &end)
          .ok());
  EXPECT_TRUE(TcpPoseFromJoints(arm.model, end, arm.flange_T_tcp).isApprox(r, 1e-6));
  // Turning the tool about its own axis in place moves the last joint only.
  const Eigen::Isometry3d turned = ToolDown(g.translation(), 1.3);
  ASSERT_TRUE(CheckStraightMove(arm.model, arm.flange_T_tcp, arm.joints, g, turned,
                                StraightMoveOptions(), &end)
                  .ok());
  EXPECT_NEAR(std::abs(end[5] - arm.joints[5]), 1.0, 1e-6);
  for (int i = 0; i < 5; ++i) EXPECT_NEAR(end[i], arm.joints[i], 1e-6) << i;
}

TEST(StraightMoveTest, StretchingTheElbowOutIsASingularity) {
  // Lifting straight up far in front of the robot: the arm stretches out
  // and the elbow would have to turn ever faster.
  const Eigen::Isometry3d g = ToolDown(Eigen::Vector3d(0.0, -0.6, 0.45), 0.0);
  const PickArm arm = ArmAt(g);
  const absl::Status status =
      CheckStraightMove(arm.model, arm.flange_T_tcp, arm.joints, g, RaisedAlongBaseZ(g, 0.25),
                        StraightMoveOptions(), nullptr);
  ASSERT_EQ(status.code(), absl::StatusCode::kFailedPrecondition) << status;
  EXPECT_THAT(status.message(), HasSubstr("passes a singularity at (0.000, -0.600, "));
  EXPECT_THAT(status.message(), HasSubstr("joint 3"));
  // Far beyond the reach: the line leaves it.
  const absl::Status out = CheckStraightMove(arm.model, arm.flange_T_tcp, arm.joints, g,
                                             ToolDown(Eigen::Vector3d(0.0, -1.5, 0.45), 0.0),
                                             StraightMoveOptions(), nullptr);
  ASSERT_EQ(out.code(), absl::StatusCode::kFailedPrecondition) << out;
  EXPECT_THAT(out.message(), AnyOf(HasSubstr("leaves the arm's reach"), HasSubstr("singularity")));
}

TEST(StraightMoveTest, BadInputIsInvalidArgument) {
  const Eigen::Isometry3d g = ToolDown(Eigen::Vector3d(0.1, -0.5, 0.15), 0.3);
  const PickArm arm = ArmAt(g);
  // Start joints that are not at `from`.
  EXPECT_EQ(CheckStraightMove(arm.model, arm.flange_T_tcp, kHome, g, RaisedAlongBaseZ(g, 0.1),
                              StraightMoveOptions(), nullptr)
                .code(),
            absl::StatusCode::kInvalidArgument);
  StraightMoveOptions zero_speed;
  zero_speed.linear_speed_m_s = 0.0;
  EXPECT_EQ(CheckStraightMove(arm.model, arm.flange_T_tcp, arm.joints, g, RaisedAlongBaseZ(g, 0.1),
                              zero_speed, nullptr)
                .code(),
            absl::StatusCode::kInvalidArgument);
  Eigen::Isometry3d nan = g;
  nan.translation().x() = std::nan("");
  EXPECT_EQ(CheckStraightMove(arm.model, arm.flange_T_tcp, arm.joints, g, nan,
                              StraightMoveOptions(), nullptr)
                .code(),
            absl::StatusCode::kInvalidArgument);
}

TEST_F(PickPlanTest, ABoxOnlyAnotherBranchReachesIsRefused) {
  // A carton top 0.45 m up at (0, -0.322), next to the base: lifting it 0.25 m
  // with the tool's x along base x stretches the elbow out (the demo's failing
  // retrieve); the other tool rotations, and the slot behind the robot, are
  // reached only by flipping the arm's configuration, which free moves never do.
  const BoxInBase box = BoxToBase(FlatBox(Eigen::Vector3d(0.0, -0.322, 0.375), 0.0),
                                  Eigen::Isometry3d::Identity(), kCarton);
  // Tool x along base x, the arm in the emulator's start-up configuration.
  const Eigen::Isometry3d now = ToolDown(Eigen::Vector3d(0.0, -0.3, 0.5), 0.0);
  const PickArm arm = ArmAt(now);
  const std::array<Eigen::Isometry3d, 4> grasps =
      GraspCandidates(box, Eigen::Quaterniond(now.linear()));
  ASSERT_NEAR(grasps[0].linear().col(0).x(), 1.0, kTol);  // the preferred grasp
  // The preferred grasp, as the controller would run it, fails on the lift.
  {
    absl::StatusOr<ur::Joints> at_m = ur::InverseKinematics(
        arm.model, RaisedAlongBaseZ(grasps[0], 0.10) * arm.flange_T_tcp.inverse(), arm.joints);
    ASSERT_TRUE(at_m.ok());
    ur::Joints at_g{};
    ASSERT_TRUE(CheckStraightMove(arm.model, arm.flange_T_tcp, *at_m,
                                  RaisedAlongBaseZ(grasps[0], 0.10), grasps[0],
                                  StraightMoveOptions(), &at_g)
                    .ok());
    EXPECT_FALSE(CheckStraightMove(arm.model, arm.flange_T_tcp, at_g, grasps[0],
                                   RaisedAlongBaseZ(grasps[0], 0.25), StraightMoveOptions(),
                                   nullptr)
                     .ok());
  }
  absl::StatusOr<PickPlan> plan = PlanPick(arm, box, kCarton, slot_, 0, waypoints_, workspace_);
  ASSERT_EQ(plan.status().code(), absl::StatusCode::kFailedPrecondition) << plan.status();
  EXPECT_THAT(plan.status().message(), HasSubstr("straight move G->R (retrieve)"));
  EXPECT_THAT(plan.status().message(), HasSubstr("nor with any other tool rotation"));
}

// The branch of a joint vector as the planner tells them apart: the wrist in
// front of the shoulder along the arm's heading, and the elbow's sign.
std::pair<bool, bool> BranchOf(const ur::Joints& q) {
  const ur::DhParameters& dh = ur::NominalDh(ur::ArmModel::kUr5e);
  const double reach = -(dh.a[1] * std::cos(q[1]) + dh.a[2] * std::cos(q[1] + q[2]));
  return {reach >= 0.0, std::remainder(q[2], 2.0 * M_PI) >= 0.0};
}

TEST_F(PickPlanTest, FreeMovesKeepTheReferenceBranchForASlotBehindTheRobot) {
  // The box in front of the base, the slot behind it: the nearest IK
  // solution for the slot from over the box reaches back over the shoulder;
  // the planner turns the base instead, and sends the joints it chose.
  const BoxInBase box = BoxToBase(FlatBox(Eigen::Vector3d(0.1, -0.5, 0.075), 0.0),
                                  Eigen::Isometry3d::Identity(), kCarton);
  PickArm arm = ArmAt(ToolDown(Eigen::Vector3d(0.0, -0.4, 0.45), 0.0));
  arm.branch_reference = arm.joints;
  const Eigen::Isometry3d behind = Pose(Eigen::Vector3d(0.1, 0.5, 0.0), Eigen::Matrix3d::Identity());
  absl::StatusOr<PickPlan> plan = PlanPick(arm, box, kCarton, behind, 0, waypoints_, workspace_);
  ASSERT_TRUE(plan.ok()) << plan.status();
  const std::pair<bool, bool> want = BranchOf(arm.joints);
  EXPECT_EQ(BranchOf(plan->approach_joints), want);
  EXPECT_EQ(BranchOf(plan->place_above_joints), want);
  // The base turned about half a turn to face the slot, within the limits.
  EXPECT_GT(std::abs(plan->place_above_joints[0] - plan->retrieve_joints[0]), 2.0);
  for (double q : plan->place_above_joints) EXPECT_LE(std::abs(q), 2.0 * M_PI);
  EXPECT_TRUE(TcpPoseFromJoints(arm.model, plan->place_above_joints, arm.flange_T_tcp)
                  .isApprox(plan->place_above, 1e-6));
}

TEST_F(PickPlanTest, HeightsComeFromThePile) {
  // A carton 0.15 m up, next to a pile 0.60 m high: M 5 cm above the pile's
  // top, R with the held box's bottom 5 cm above it.
  BoxInBase box = BoxToBase(FlatBox(Eigen::Vector3d(0.1, -0.5, 0.075), 0.0),
                            Eigen::Isometry3d::Identity(), kCarton);
  EXPECT_DOUBLE_EQ(ApproachDistance(box, waypoints_), waypoints_.approach_distance_m);
  EXPECT_DOUBLE_EQ(RetrieveHeight(box, waypoints_), waypoints_.retrieve_height_m);
  box.pile_top_z_m = 0.60;
  EXPECT_NEAR(ApproachDistance(box, waypoints_), 0.60 + 0.05 - 0.15, 1e-9);
  EXPECT_NEAR(RetrieveHeight(box, waypoints_), 0.60 + 0.05 + 0.15 - 0.15, 1e-9);
  // Above the slot: the held box's bottom 5 cm above its layer's tops.
  EXPECT_NEAR(PlaceApproachHeight(box, waypoints_), 0.15 + 0.05, 1e-9);
  // The box itself the top: the configured minimums.
  box.pile_top_z_m = 0.15;
  EXPECT_DOUBLE_EQ(ApproachDistance(box, waypoints_), waypoints_.approach_distance_m);
  EXPECT_DOUBLE_EQ(RetrieveHeight(box, waypoints_), waypoints_.retrieve_height_m);
}

TEST_F(PickPlanTest, EveryOrientationFailingIsRefusedNamingTheMove) {
  // 0.6 m out and lifted to 0.70: every tool rotation stretches the arm out.
  const BoxInBase box = BoxToBase(FlatBox(Eigen::Vector3d(0.0, -0.6, 0.375), 0.0),
                                  Eigen::Isometry3d::Identity(), kCarton);
  const PickArm arm = ArmAt(ToolDown(Eigen::Vector3d(0, 0.3, 0.5), 0.0));
  absl::StatusOr<PickPlan> plan = PlanPick(arm, box, kCarton, slot_, 0, waypoints_, workspace_);
  ASSERT_EQ(plan.status().code(), absl::StatusCode::kFailedPrecondition) << plan.status();
  EXPECT_THAT(plan.status().message(),
              HasSubstr("straight move G->R (retrieve) passes a singularity"));
  EXPECT_THAT(plan.status().message(), HasSubstr("nor with any other tool rotation"));

  // A slot out of the arm's reach.
  const BoxInBase reachable = BoxToBase(FlatBox(Eigen::Vector3d(0.1, -0.5, 0.075), 0.0),
                                        Eigen::Isometry3d::Identity(), kCarton);
  plan = PlanPick(arm, reachable, kCarton,
                  Pose(Eigen::Vector3d(0.0, 1.5, 0.0), Eigen::Matrix3d::Identity()), 0, waypoints_,
                  workspace_);
  ASSERT_EQ(plan.status().code(), absl::StatusCode::kFailedPrecondition) << plan.status();
  EXPECT_THAT(plan.status().message(), HasSubstr("waypoint place_above at (0.000, 1.500, "));
  EXPECT_THAT(plan.status().message(), HasSubstr("not reachable"));
}

}  // namespace
}  // namespace cornerpose::robot_client
