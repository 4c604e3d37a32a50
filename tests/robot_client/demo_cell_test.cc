// The shipped deploy/config/robot_client.textproto describes a cell that
// works: a carton on the table under the camera is selected and planned into
// every slot of the pallet from the clear pose, with every waypoint inside
// the workspace and reachable by the UR5e, and the program renders.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "common/perception/types.h"  // the camera model of the view check
#include "robot_client/config/robot_config.h"
#include "robot_client/planning/grasp_geometry.h"
#include "robot_client/planning/pick_plan.h"
#include "robot_client/planning/pick_selection.h"
#include "robot_client/planning/place_pattern.h"
#include "robot_client/planning/straight_move.h"
#include "robot_client/planning/urscript_program.h"
#include "robot_client/ur/kinematics.h"
#include "tests/robot_client/test_config.h"
#include "tests/robot_client/test_poses.h"

namespace cornerpose::robot_client {
namespace {

using testing::ToolDownAt;

// A carton lying flat on the table (base z = 0) at (x, y), yawed, as the
// camera of `options` sees it.
DetectedBox CartonOnTable(const RobotClientOptions& options, double x, double y, double yaw) {
  Eigen::Isometry3d base_T_box = Eigen::Isometry3d::Identity();
  base_T_box.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  base_T_box.translation() = Eigen::Vector3d(x, y, 0.5 * options.perception.box.h);
  DetectedBox box;
  box.camera_T_box = options.base_T_camera.inverse() * base_T_box;
  box.grasp_face = BoxFace::kPlusZ;
  box.score = 0.9;
  return box;
}

TEST(DemoCellTest, CartonUnderTheCameraGoesIntoEverySlot) {
  absl::StatusOr<RobotClientOptions> options = LoadRobotClientConfig(testing::ShippedConfigPath());
  ASSERT_TRUE(options.ok()) << options.status();
  const ur::Joints clear = *options->clear_joints;
  const Reachability reachable =
      MakeIkReachability(options->robot.arm_model, options->gripper.flange_T_tcp);
  ASSERT_TRUE(
      reachable(TcpPoseFromJoints(options->robot.arm_model, clear, options->gripper.flange_T_tcp)));

  // The camera's image centre on the table, and a few cartons around it.
  const Eigen::Vector3d centre = options->base_T_camera.translation();
  const std::vector<DetectedBox> boxes = {
      CartonOnTable(*options, centre.x(), centre.y(), 0.3),
      CartonOnTable(*options, centre.x() + 0.25, centre.y() - 0.2, -1.0),
      CartonOnTable(*options, centre.x() - 0.3, centre.y() + 0.15, 2.0),
  };
  const PickSelection selection =
      SelectPick(boxes, options->base_T_camera, options->perception.box, options->selection,
                 options->workspace, options->waypoints, reachable);
  for (const BoxVerdict& v : selection.verdicts) {
    EXPECT_TRUE(v.accepted) << v.index << ": " << v.reason;
  }
  ASSERT_TRUE(selection.chosen.has_value());

  for (const BoxVerdict& verdict : selection.verdicts) {
    for (int slot = 0; slot < SlotCount(options->place_pattern); ++slot) {
      SCOPED_TRACE(::testing::Message() << "box " << verdict.index << " slot " << slot);
      absl::StatusOr<PickPlan> plan = PlanPickForSlot(*options, clear, verdict.box, slot);
      ASSERT_TRUE(plan.ok()) << plan.status();
      for (const Eigen::Isometry3d* pose :
           {&plan->approach, &plan->grasp, &plan->retrieve, &plan->place_above, &plan->place}) {
        EXPECT_TRUE(options->workspace.Contains(pose->translation()));
        EXPECT_TRUE(reachable(*pose));
      }
      // The carton's top is grasped, and it lands on the slot.
      EXPECT_NEAR(plan->grasp.translation().z(), options->perception.box.h, 1e-9);
      absl::StatusOr<Eigen::Isometry3d> base_T_slot = SlotPose(options->place_pattern, slot);
      ASSERT_TRUE(base_T_slot.ok());
      EXPECT_TRUE(plan->place.translation().isApprox(
          base_T_slot->translation() + Eigen::Vector3d(0, 0, options->perception.box.h), 1e-9));
      absl::StatusOr<std::string> program =
          RenderPickProgram(PickProgramName(slot), *plan, options->gripper, options->motion, clear);
      EXPECT_TRUE(program.ok()) << program.status();
    }
  }
  // The pallet holds 12; the 13th pick has nowhere to go.
  EXPECT_EQ(PlanPickForSlot(*options, clear, selection.verdicts[0].box, 12).status().code(),
            absl::StatusCode::kResourceExhausted);
}

// The demo's failing retrieve (the emulator stopped it with
// runtime_error_movel_joint_jump): from the start-up joints a movej to G
// (0, -0.322, 0.450), tool down with its x along base x, then straight up to
// R at 0.680: the elbow stretches out. An ordinary retrieve off the table
// passes.
TEST(DemoCellTest, TheDemosSingularRetrieveIsRejected) {
  absl::StatusOr<RobotClientOptions> options = LoadRobotClientConfig(testing::ShippedConfigPath());
  ASSERT_TRUE(options.ok()) << options.status();
  const ur::ArmModel model = options->robot.arm_model;
  const Eigen::Isometry3d& flange_T_tcp = options->gripper.flange_T_tcp;
  StraightMoveOptions straight;
  straight.linear_speed_m_s = options->motion.linear_speed_m_s;

  const Eigen::Isometry3d g = ToolDownAt(0.0, -0.322, 0.450, 0.0);
  absl::StatusOr<ur::Joints> at_g =
      ur::InverseKinematics(model, g * flange_T_tcp.inverse(), testing::kEmulatorHomeJoints);
  ASSERT_TRUE(at_g.ok()) << at_g.status();
  const absl::Status status = CheckStraightMove(
      model, flange_T_tcp, *at_g, g, ToolDownAt(0.0, -0.322, 0.680, 0.0), straight, nullptr);
  ASSERT_EQ(status.code(), absl::StatusCode::kFailedPrecondition) << status;
  EXPECT_THAT(status.message(),
              ::testing::HasSubstr("passes a singularity at (0.000, -0.322, 0.6"));

  const Eigen::Isometry3d low = ToolDownAt(0.0, -0.5, 0.15, 0.0);
  absl::StatusOr<ur::Joints> at_low =
      ur::InverseKinematics(model, low * flange_T_tcp.inverse(), testing::kEmulatorHomeJoints);
  ASSERT_TRUE(at_low.ok()) << at_low.status();
  ur::Joints end{};
  EXPECT_TRUE(CheckStraightMove(model, flange_T_tcp, *at_low, low, ToolDownAt(0.0, -0.5, 0.40, 0.0),
                                straight, &end)
                  .ok());
}

// Whatever PlanPickForSlot returns runs: for cartons all over the pick area
// (on the table and stacked one and two high, several yaws), from the
// emulator's start-up joints and from the clear pose, each returned plan's
// movej joint vectors reach their waypoints and its straight moves pass
// CheckStraightMove again from them. Most of them plan.
TEST(DemoCellTest, PlannedStraightMovesAreClearOfSingularities) {
  absl::StatusOr<RobotClientOptions> options = LoadRobotClientConfig(testing::ShippedConfigPath());
  ASSERT_TRUE(options.ok()) << options.status();
  const ur::ArmModel model = options->robot.arm_model;
  const Eigen::Isometry3d& flange_T_tcp = options->gripper.flange_T_tcp;
  const Eigen::Isometry3d tcp_T_flange = flange_T_tcp.inverse();
  StraightMoveOptions straight;
  straight.linear_speed_m_s = options->motion.linear_speed_m_s;
  const Eigen::Vector3d centre = options->base_T_camera.translation();
  int planned = 0, tried = 0;
  for (const ur::Joints& start : {testing::kEmulatorHomeJoints, *options->clear_joints}) {
    for (double dx = -0.3; dx <= 0.3001; dx += 0.15) {
      for (double dy = -0.25; dy <= 0.2501; dy += 0.125) {
        for (double top : {0.15, 0.30, 0.45}) {
          for (double yaw : {0.0, 0.7, 1.6}) {
            DetectedBox carton = CartonOnTable(*options, centre.x() + dx, centre.y() + dy, yaw);
            carton.camera_T_box.translation() +=
                options->base_T_camera.inverse().linear() *
                Eigen::Vector3d(0, 0, top - options->perception.box.h);
            const BoxInBase box =
                BoxToBase(carton, options->base_T_camera, options->perception.box);
            ASSERT_NEAR(box.grasp_point.z(), top, 1e-9);
            const int slot = tried % SlotCount(options->place_pattern);
            ++tried;
            absl::StatusOr<PickPlan> plan = PlanPickForSlot(*options, start, box, slot);
            if (!plan.ok()) {
              EXPECT_EQ(plan.status().code(), absl::StatusCode::kFailedPrecondition);
              continue;
            }
            ++planned;
            SCOPED_TRACE(::testing::Message() << "box at " << box.grasp_point.transpose() << " yaw "
                                              << yaw << " slot " << slot);
            EXPECT_EQ(plan->initial_joints, start);
            // The movej targets are joint vectors that reach the waypoints.
            const auto reaches = [&](const ur::Joints& q, const Eigen::Isometry3d& tcp) {
              const Eigen::Isometry3d at = ur::ForwardKinematics(model, q) * flange_T_tcp;
              return (at.translation() - tcp.translation()).norm() < 1e-6 &&
                     Eigen::AngleAxisd(at.linear().transpose() * tcp.linear()).angle() < 1e-6;
            };
            EXPECT_TRUE(reaches(plan->approach_joints, plan->approach));
            EXPECT_TRUE(reaches(plan->place_above_joints, plan->place_above));
            const ur::Joints* at_m = &plan->approach_joints;
            ur::Joints at_g{}, at_r{}, at_f{}, back{};
            EXPECT_TRUE(CheckStraightMove(model, flange_T_tcp, *at_m, plan->approach, plan->grasp,
                                          straight, &at_g)
                            .ok());
            EXPECT_TRUE(CheckStraightMove(model, flange_T_tcp, at_g, plan->grasp, plan->retrieve,
                                          straight, &at_r)
                            .ok());
            const ur::Joints* at_above = &plan->place_above_joints;
            EXPECT_TRUE(CheckStraightMove(model, flange_T_tcp, *at_above, plan->place_above,
                                          plan->place, straight, &at_f)
                            .ok());
            EXPECT_TRUE(CheckStraightMove(model, flange_T_tcp, at_f, plan->place, plan->place_above,
                                          straight, &back)
                            .ok());
          }
        }
      }
    }
  }
  std::cerr << planned << " of " << tried << " picks planned\n";
  EXPECT_GT(planned, tried / 2);
}

// The clear pose keeps the arm out of the picture: every joint frame's origin,
// the midpoints between them and the TCP project outside a VGA image (the
// default intrinsics, 62 x 49 degrees) or lie behind the camera.
TEST(DemoCellTest, ClearPoseIsOutOfTheCamerasView) {
  absl::StatusOr<RobotClientOptions> options = LoadRobotClientConfig(testing::ShippedConfigPath());
  ASSERT_TRUE(options.ok()) << options.status();
  const CameraIntrinsics camera;
  // What moves: the base and the shoulder joint (frame 1) stay where they
  // are (at the image's top edge in this cell), so from the elbow (frame 2)
  // on, with the upper arm's midpoint.
  std::vector<Eigen::Vector3d> points;
  for (int k = 1; k <= 6; ++k) {
    // FK with the parameters of joints after k zeroed: the origin of frame k.
    ur::DhParameters dh = ur::NominalDh(options->robot.arm_model);
    for (int j = k; j < 6; ++j) dh.a[j] = dh.d[j] = dh.alpha[j] = 0.0;
    points.push_back(ur::ForwardKinematics(dh, *options->clear_joints).translation());
  }
  points.push_back(TcpPoseFromJoints(options->robot.arm_model, *options->clear_joints,
                                     options->gripper.flange_T_tcp)
                       .translation());
  const size_t joints = points.size();
  for (size_t i = 0; i + 1 < joints; ++i) points.push_back(0.5 * (points[i] + points[i + 1]));
  points.erase(points.begin());  // frame 1, the shoulder
  const Eigen::Isometry3d camera_T_base = options->base_T_camera.inverse();
  for (const Eigen::Vector3d& base_p : points) {
    const Eigen::Vector3d c = camera_T_base * base_p;
    if (c.z() <= 0) continue;
    const double u = camera.fx * c.x() / c.z() + camera.cx;
    const double v = camera.fy * c.y() / c.z() + camera.cy;
    EXPECT_TRUE(u < 0 || u >= camera.width || v < 0 || v >= camera.height)
        << "arm point " << base_p.transpose() << " is in the image at (" << u << ", " << v << ")";
  }
}

BoxFace FaceFromName(const std::string& name) {
  for (int f = 0; f < 6; ++f) {
    if (name == BoxFaceName(static_cast<BoxFace>(f))) return static_cast<BoxFace>(f);
  }
  ADD_FAILURE() << "unknown face " << name;
  return BoxFace::kPlusZ;
}

// The recorded frames of the cell (data/frames/cell, what the end-to-end
// test replays) were taken from the mounting the shipped base_pose_camera
// describes: through it every ground-truth box rests on or above the table
// (base z = 0), the heap stands on it, and in every frame a box is chosen
// and planned into the first slot.
TEST(DemoCellTest, RecordedCellFramesMatchTheCameraMounting) {
  absl::StatusOr<RobotClientOptions> options = LoadRobotClientConfig(testing::ShippedConfigPath());
  ASSERT_TRUE(options.ok()) << options.status();
  const Reachability reachable =
      MakeIkReachability(options->robot.arm_model, options->gripper.flange_T_tcp);
  int frames = 0;
  for (const auto& entry : std::filesystem::directory_iterator(
           std::filesystem::path(CORNERPOSE_SOURCE_DIR) / "data/frames/cell")) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("cell_", 0) != 0 || entry.path().extension() != ".json") continue;
    SCOPED_TRACE(name);
    ++frames;
    std::ifstream in(entry.path());
    const nlohmann::json truth = nlohmann::json::parse(in);
    std::vector<DetectedBox> boxes;
    double lowest = 1e9;
    for (const nlohmann::json& b : truth.at("boxes")) {
      Eigen::Matrix4d T;
      for (int r = 0; r < 4; ++r) {
        for (int c = 0; c < 4; ++c) T(r, c) = b.at("T_cam_box").at(r).at(c).get<double>();
      }
      DetectedBox box;
      box.camera_T_box.matrix() = T;
      box.grasp_face = FaceFromName(b.at("grasp_face").get<std::string>());
      box.score = b.at("visib_fract").get<double>();
      const Eigen::Isometry3d base_T_box = options->base_T_camera * box.camera_T_box;
      const Eigen::Vector3d half = 0.5 * options->perception.box.vec();
      double bottom = 1e9;
      for (int corner = 0; corner < 8; ++corner) {
        const Eigen::Vector3d p(corner & 1 ? half.x() : -half.x(),
                                corner & 2 ? half.y() : -half.y(),
                                corner & 4 ? half.z() : -half.z());
        bottom = std::min(bottom, (base_T_box * p).z());
      }
      EXPECT_GE(bottom, -0.002) << "box " << b.at("id") << " reaches under the table";
      lowest = std::min(lowest, bottom);
      if (b.at("pickable").get<bool>() && box.score > 0.9) boxes.push_back(box);
    }
    EXPECT_NEAR(lowest, 0.0, 0.002) << "the heap does not stand on the table";
    const PickSelection selection =
        SelectPick(boxes, options->base_T_camera, options->perception.box, options->selection,
                   options->workspace, options->waypoints, reachable);
    ASSERT_TRUE(selection.chosen.has_value()) << boxes.size() << " fully visible boxes";
    // The daemon's way: the best box that plans (its straight moves clear
    // of singularities), falling back down the ranking.
    std::string failures;
    bool planned = false;
    for (int index : selection.ranked) {
      absl::StatusOr<PickPlan> plan =
          PlanPickForSlot(*options, *options->clear_joints, selection.verdicts[index].box, 0);
      if (plan.ok()) {
        planned = true;
        break;
      }
      failures += absl::StrCat("\n  box ", index, ": ", plan.status().message());
    }
    EXPECT_TRUE(planned) << "no box plans:" << failures;
  }
  EXPECT_GT(frames, 0) << "no recorded cell frames";
}

}  // namespace
}  // namespace cornerpose::robot_client
