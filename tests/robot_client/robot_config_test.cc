// LoadRobotClientConfig: the shipped file loads with the values it states;
// each kind of bad file fails with INVALID_ARGUMENT naming the file and what
// is wrong; a missing file is NOT_FOUND.
#include "robot_client/config/robot_config.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <string>
#include <utility>
#include <vector>

#include "tests/robot_client/test_config.h"

namespace cornerpose::robot_client {
namespace {

using ::testing::HasSubstr;
using testing::ReadFile;
using testing::ShippedConfigPath;
using testing::WriteTempFile;

TEST(RobotConfigTest, ShippedConfigLoadsWithItsValues) {
  absl::StatusOr<RobotClientOptions> options = LoadRobotClientConfig(ShippedConfigPath());
  ASSERT_TRUE(options.ok()) << options.status();
  EXPECT_TRUE(options->Validate().ok());
  EXPECT_EQ(options->perception.server_address, "localhost:50051");
  EXPECT_EQ(options->perception.source, "cell");
  EXPECT_EQ(options->perception.box_model, "carton_s");
  EXPECT_DOUBLE_EQ(options->perception.box.l, 0.30);
  EXPECT_DOUBLE_EQ(options->perception.box.h, 0.15);
  EXPECT_EQ(options->robot.host, "127.0.0.1");
  EXPECT_EQ(options->robot.dashboard_port, 29999);
  EXPECT_EQ(options->robot.primary_port, 30001);
  EXPECT_EQ(options->robot.rtde_port, 30004);
  EXPECT_EQ(options->robot.arm_model, ur::ArmModel::kUr5e);
  // The camera looks down: its optical axis is base -z.
  EXPECT_TRUE(options->base_T_camera.linear().col(2).isApprox(-Eigen::Vector3d::UnitZ(), 1e-9));
  EXPECT_TRUE(options->base_T_camera.translation().isApprox(Eigen::Vector3d(0, -0.5, 1.3)));
  EXPECT_TRUE(options->workspace.Contains(Eigen::Vector3d(0, -0.5, 0.15)));
  EXPECT_FALSE(options->workspace.Contains(Eigen::Vector3d(0, -0.5, 0.0)));
  EXPECT_TRUE(options->gripper.flange_T_tcp.translation().isApprox(Eigen::Vector3d(0, 0, 0.1)));
  EXPECT_EQ(options->gripper.suction_output, SuctionOutputKind::kTool);
  EXPECT_EQ(options->place_pattern.rows, 2);
  EXPECT_EQ(options->place_pattern.columns, 3);
  EXPECT_EQ(options->place_pattern.layers, 2);
  EXPECT_EQ(options->place_pattern.slot_count(), 12);
  ASSERT_TRUE(options->clear_joints.has_value());
  EXPECT_DOUBLE_EQ((*options->clear_joints)[4], -1.5708);
  EXPECT_EQ(options->status_listen_address, "127.0.0.1:50061");
  EXPECT_FALSE(options->dry_run);
  EXPECT_EQ(options->max_picks, 0);
}

TEST(RobotConfigTest, MissingFileIsNotFound) {
  absl::StatusOr<RobotClientOptions> options =
      LoadRobotClientConfig(::testing::TempDir() + "/no_such_robot_client.textproto");
  EXPECT_EQ(options.status().code(), absl::StatusCode::kNotFound) << options.status();
}

TEST(RobotConfigTest, DirectoryIsInvalidArgument) {
  absl::StatusOr<RobotClientOptions> options = LoadRobotClientConfig(::testing::TempDir());
  EXPECT_EQ(options.status().code(), absl::StatusCode::kInvalidArgument) << options.status();
}

// The shipped text with `from` (which must occur exactly once) replaced.
std::string ShippedWith(const std::string& from, const std::string& to) {
  std::string text = ReadFile(ShippedConfigPath());
  const size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << "'" << from << "' is not in the shipped config";
  EXPECT_EQ(text.find(from, at + 1), std::string::npos) << "'" << from << "' occurs twice";
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

struct BadCase {
  std::string name;
  std::string from;
  std::string to;
  std::string message;  // expected in the error
};

TEST(RobotConfigTest, EachBadValueIsInvalidArgumentWithAUsefulMessage) {
  const std::vector<BadCase> cases = {
      {"unknown_field", "dry_run: false", "dry_run: false\nbogus_field: 1", "bogus_field"},
      {"syntax", "rows: 2", "rows: 2 }", ":"},
      {"non_unit_quaternion", "orientation { w: 0 x: 1 y: 0 z: 0 }",
       "orientation { w: 0 x: 2 y: 0 z: 0 }",
       "base_pose_camera.orientation must be a unit quaternion"},
      {"zero_quaternion", "orientation { w: 1 x: 0 y: 0 z: 0 }", "orientation { }",
       "place_pattern.origin.orientation must be a unit quaternion"},
      {"empty_workspace", "min { x: -0.6 y: -0.9 z: 0.03 }", "min { x: 0.6 y: -0.9 z: 0.03 }",
       "workspace is empty: min.x 0.6 >= max.x 0.6"},
      {"no_rows", "rows: 2", "rows: 0", "place_pattern has no slots"},
      {"no_layers", "layers: 2", "layers: 0", "place_pattern has no slots"},
      {"zero_spacing", "spacing_x_m: 0.32", "spacing_x_m: 0", "place_pattern.spacing_x_m"},
      {"negative_layer_height", "layer_height_m: 0.15", "layer_height_m: -0.15",
       "place_pattern.layer_height_m must be > 0"},
      {"zero_joint_speed", "joint_speed_rad_s: 1.05", "joint_speed_rad_s: 0",
       "motion.joint_speed_rad_s must be > 0"},
      {"negative_linear_speed", "linear_speed_m_s: 0.1", "linear_speed_m_s: -0.1",
       "motion.linear_speed_m_s must be > 0"},
      {"too_fast", "linear_speed_m_s: 0.1", "linear_speed_m_s: 3", "motion.linear_speed_m_s"},
      {"zero_approach", "approach_distance_m: 0.10", "approach_distance_m: 0",
       "waypoints.approach_distance_m must be > 0"},
      {"five_clear_joints", ", -0.3907]", "]", "clear_joints_rad must hold exactly 6"},
      {"clear_pose_outside_workspace", "max { x: 0.6 y: 0.8 z: 0.9 }",
       "max { x: 0.6 y: 0.3 z: 0.9 }", "clear_joints_rad put the TCP at"},
      {"no_source", "source: \"cell\"", "", "perception.source is required"},
      {"no_box", "box_model: \"carton_s\"", "", "perception: set box"},
      {"unknown_box_model", "box_model: \"carton_s\"", "box_model: \"crate\"",
       "perception.box_model: unknown box model"},
      {"zero_box_side", "box_model: \"carton_s\"", "box { l: 0.3 b: 0 h: 0.15 }", "perception.box"},
      {"unknown_arm", "arm_model: \"ur5e\"", "arm_model: \"ur10\"", "robot.arm_model"},
      {"no_host", "host: \"127.0.0.1\"", "", "robot.host is required"},
      {"bad_port", "rtde_port: 30004", "rtde_port: 70000", "robot.rtde_port"},
      {"tilt_over_90", "max_grasp_tilt_deg: 30", "max_grasp_tilt_deg: 95",
       "selection.max_grasp_tilt_deg"},
      {"score_over_1", "min_score: 0.0", "min_score: 1.5", "selection.min_score"},
      {"tool_output_2", "suction_output_index: 0", "suction_output_index: 2",
       "gripper.suction_output_index must be in [0, 1]"},
      {"negative_settle", "grasp_settle_s: 0.3", "grasp_settle_s: -1", "gripper.grasp_settle_s"},
      {"backoff_max_below_initial", "reconnect_max_s: 10", "reconnect_max_s: 0.1",
       "perception.reconnect_max_s"},
      {"tcp_rotation_over_pi", "rotation_vector { x: 0 y: 0 z: 0 }",
       "rotation_vector { x: 0 y: 0 z: 4 }", "gripper.tcp_offset.rotation_vector"},
  };
  for (const BadCase& c : cases) {
    SCOPED_TRACE(c.name);
    const std::string path = WriteTempFile(c.name + ".textproto", ShippedWith(c.from, c.to));
    absl::StatusOr<RobotClientOptions> options = LoadRobotClientConfig(path);
    ASSERT_FALSE(options.ok()) << "loaded";
    EXPECT_EQ(options.status().code(), absl::StatusCode::kInvalidArgument) << options.status();
    EXPECT_THAT(options.status().message(), HasSubstr(path));
    EXPECT_THAT(options.status().message(), HasSubstr(c.message));
  }
}

TEST(RobotConfigTest, SyntaxErrorsNameTheLine) {
  const std::string path =
      WriteTempFile("line.textproto", "perception {\n  source: \"x\"\n  bogus: 1\n}\n");
  absl::StatusOr<RobotClientOptions> options = LoadRobotClientConfig(path);
  ASSERT_EQ(options.status().code(), absl::StatusCode::kInvalidArgument) << options.status();
  EXPECT_THAT(options.status().message(), HasSubstr("3:"));
  EXPECT_THAT(options.status().message(), HasSubstr("bogus"));
}

TEST(RobotConfigTest, UnsetFieldsTakeTheDefaults) {
  const std::string text = R"(
perception { source: "s" box { l: 0.4 b: 0.3 h: 0.25 } }
robot { host: "arm" }
base_pose_camera { orientation { w: 1 } }
workspace { min { x: -1 y: -1 z: -1 } max { x: 1 y: 1 z: 1 } }
place_pattern { origin { orientation { w: 1 } } }
clear_joints_rad: [0, -1.5708, 1.5708, -1.5708, -1.5708, 0]
)";
  absl::StatusOr<RobotClientOptions> options =
      LoadRobotClientConfig(WriteTempFile("minimal.textproto", text));
  ASSERT_TRUE(options.ok()) << options.status();
  const RobotClientOptions defaults;
  EXPECT_EQ(options->perception.server_address, "localhost:50051");
  EXPECT_TRUE(options->perception.box_model.empty());
  EXPECT_DOUBLE_EQ(options->perception.box.b, 0.3);
  EXPECT_EQ(options->robot.dashboard_port, 29999);
  EXPECT_EQ(options->robot.arm_model, ur::ArmModel::kUr5e);
  EXPECT_DOUBLE_EQ(options->robot.rtde_frequency_hz, defaults.robot.rtde_frequency_hz);
  EXPECT_DOUBLE_EQ(options->selection.max_grasp_tilt_deg, 30.0);
  EXPECT_TRUE(options->gripper.flange_T_tcp.isApprox(Eigen::Isometry3d::Identity()));
  EXPECT_DOUBLE_EQ(options->waypoints.retrieve_height_m, defaults.waypoints.retrieve_height_m);
  EXPECT_EQ(options->place_pattern.slot_count(), 1);
  // The layer height defaults to the box height.
  EXPECT_DOUBLE_EQ(options->place_pattern.layer_height_m, 0.25);
  EXPECT_DOUBLE_EQ(options->motion.linear_speed_m_s, defaults.motion.linear_speed_m_s);
  EXPECT_EQ(options->status_listen_address, "127.0.0.1:50061");
}

TEST(RobotConfigTest, DefaultStructsNeedTheRequiredFields) {
  RobotClientOptions options;
  EXPECT_THAT(options.Validate().message(), HasSubstr("perception.source is required"));
  EXPECT_TRUE(SelectionOptions().Validate().ok());
  EXPECT_TRUE(GripperOptions().Validate().ok());
  EXPECT_TRUE(WaypointOptions().Validate().ok());
  EXPECT_TRUE(MotionOptions().Validate().ok());
  EXPECT_FALSE(Workspace().Validate().ok());
  EXPECT_FALSE(PlacePatternOptions().Validate().ok());  // layer height unset
}

}  // namespace
}  // namespace cornerpose::robot_client
