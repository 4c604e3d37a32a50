// The sections of RobotClientConfig one by one (robot_config_proto.h): what
// each takes from the file, the defaults it leaves, and the errors it names.
#include "robot_client/config/robot_config_proto.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace cornerpose::robot_client {
namespace {

using ::testing::HasSubstr;

TEST(PerceptionFromProtoTest, ExplicitBoxModelOrNeither) {
  v1::PerceptionClientConfig perception;
  perception.set_source("cell");
  PerceptionClientOptions options;
  EXPECT_THAT(PerceptionFromProto(perception, &options).message(),
              HasSubstr("perception: set box"));

  perception.set_box_model("carton_l");
  ASSERT_TRUE(PerceptionFromProto(perception, &options).ok());
  EXPECT_EQ(options.box_model, "carton_l");
  EXPECT_EQ(options.box.h, 0.25);
  EXPECT_EQ(options.server_address, "localhost:50051");  // unset: the default

  perception.mutable_box()->set_l(0.5);
  perception.mutable_box()->set_b(0.4);
  perception.mutable_box()->set_h(0.3);
  PerceptionClientOptions explicit_box;
  ASSERT_TRUE(PerceptionFromProto(perception, &explicit_box).ok());
  EXPECT_TRUE(explicit_box.box_model.empty());
  EXPECT_EQ(explicit_box.box.b, 0.4);
}

TEST(GripperFromProtoTest, TcpOffsetAndSuctionOutput) {
  v1::GripperConfig gripper;
  gripper.mutable_tcp_offset()->mutable_position()->set_z(0.12);
  gripper.set_suction_output(v1::SUCTION_OUTPUT_KIND_STANDARD);
  gripper.set_suction_output_index(5);
  GripperOptions options;
  ASSERT_TRUE(GripperFromProto(gripper, &options).ok());
  EXPECT_NEAR(options.flange_T_tcp.translation().z(), 0.12, 1e-12);
  EXPECT_EQ(options.suction_output, SuctionOutputKind::kStandard);
  EXPECT_EQ(options.suction_output_index, 5);

  gripper.mutable_tcp_offset()->mutable_rotation_vector()->set_x(4.0);
  EXPECT_THAT(GripperFromProto(gripper, &options).message(),
              HasSubstr("gripper.tcp_offset.rotation_vector must have |r| <= pi"));
}

TEST(PlacePatternFromProtoTest, LayerHeightDefaultsToTheBoxHeight) {
  v1::PlacePatternConfig pattern;
  PlacePatternOptions options;
  EXPECT_THAT(PlacePatternFromProto(pattern, 0.15, &options).message(),
              HasSubstr("place_pattern.origin is required"));
  pattern.mutable_origin()->mutable_orientation()->set_w(1);
  pattern.set_rows(2);
  ASSERT_TRUE(PlacePatternFromProto(pattern, 0.15, &options).ok());
  EXPECT_EQ(options.rows, 2);
  EXPECT_EQ(options.columns, 1);
  EXPECT_EQ(options.layer_height_m, 0.15);
  pattern.set_layer_height_m(0.2);
  ASSERT_TRUE(PlacePatternFromProto(pattern, 0.15, &options).ok());
  EXPECT_EQ(options.layer_height_m, 0.2);

  pattern.mutable_origin()->mutable_orientation()->set_w(0.5);
  EXPECT_THAT(PlacePatternFromProto(pattern, 0.15, &options).message(),
              HasSubstr("place_pattern.origin.orientation must be a unit quaternion"));
}

TEST(RunFromProtoTest, ClearJointsMustBeSix) {
  v1::RobotClientConfig config;
  for (int i = 0; i < 5; ++i) config.add_clear_joints_rad(0.1 * i);
  RobotClientOptions options;
  EXPECT_THAT(RunFromProto(config, &options).message(),
              HasSubstr("clear_joints_rad must hold exactly 6 joint angles, got 5"));
  config.add_clear_joints_rad(0.5);
  config.set_max_picks(3);
  ASSERT_TRUE(RunFromProto(config, &options).ok());
  ASSERT_TRUE(options.clear_joints.has_value());
  EXPECT_EQ((*options.clear_joints)[5], 0.5);
  EXPECT_EQ(options.max_picks, 3);
  EXPECT_EQ(options.status_listen_address, "127.0.0.1:50061");
}

}  // namespace
}  // namespace cornerpose::robot_client
