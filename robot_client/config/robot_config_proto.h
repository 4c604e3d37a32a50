// cornerpose.v1.RobotClientConfig (protobuf) -> RobotClientOptions, one
// function per section of the file. Fields left unset keep the options'
// defaults; a section converts but does not validate (the options'
// Validate() does), except what cannot be represented: an unknown box model
// or arm, a non-unit quaternion, a missing required section. Errors name the
// field ("perception.box_model: ...", "place_pattern.origin.orientation ...").
#pragma once

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "cornerpose/v1/robot_client_config.pb.h"
#include "robot_client/config/robot_config.h"

namespace cornerpose::robot_client {

// The whole file, section by section, in the order below.
absl::StatusOr<RobotClientOptions> OptionsFromProto(const v1::RobotClientConfig& config);

// Each section into its part of the options.
absl::Status PerceptionFromProto(const v1::PerceptionClientConfig& perception,
                                 PerceptionClientOptions* options);
absl::Status RobotFromProto(const v1::RobotConnectionConfig& robot,
                            RobotConnectionOptions* options);
// base_pose_camera and workspace, both required.
absl::Status CellGeometryFromProto(const v1::RobotClientConfig& config,
                                   RobotClientOptions* options);
void SelectionFromProto(const v1::SelectionConfig& selection, SelectionOptions* options);
absl::Status GripperFromProto(const v1::GripperConfig& gripper, GripperOptions* options);
void WaypointsFromProto(const v1::WaypointConfig& waypoints, WaypointOptions* options);
// The layer height defaults to `box_height_m`.
absl::Status PlacePatternFromProto(const v1::PlacePatternConfig& pattern, double box_height_m,
                                   PlacePatternOptions* options);
void MotionFromProto(const v1::MotionConfig& motion, MotionOptions* options);
// clear_joints_rad (exactly 6), status_listen_address, dry_run, max_picks.
absl::Status RunFromProto(const v1::RobotClientConfig& config, RobotClientOptions* options);

}  // namespace cornerpose::robot_client
