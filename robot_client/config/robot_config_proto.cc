#include "robot_client/config/robot_config_proto.h"

#include <algorithm>
#include <cmath>

#include "absl/strings/str_cat.h"
#include "common/box/box_models.h"
#include "common/wire/geometry_wire.h"
#include "robot_client/ur/pose.h"

namespace cornerpose::robot_client {
namespace {

constexpr double kPi = 3.14159265358979323846;

absl::Status Invalid(absl::string_view message) { return absl::InvalidArgumentError(message); }

using wire::PoseFromProto;
using wire::Vector3dFromProto;

}  // namespace

absl::Status PerceptionFromProto(const v1::PerceptionClientConfig& perception,
                                 PerceptionClientOptions* p) {
  if (!perception.server_address().empty()) p->server_address = perception.server_address();
  p->tls_ca = perception.tls_ca();
  p->tls_cert = perception.tls_cert();
  p->tls_key = perception.tls_key();
  p->tls_server_name = perception.tls_server_name();
  p->source = perception.source();
  switch (perception.box_size_case()) {
    case v1::PerceptionClientConfig::kBox:
      p->box = {perception.box().l(), perception.box().b(), perception.box().h()};
      break;
    case v1::PerceptionClientConfig::kBoxModel: {
      // The expected size, for the defaults that need one (the layer
      // height); each pick uses the size the server reports it detected
      // with, which alone resolves the name the subscription sends.
      absl::StatusOr<BoxDims> dims = BoxModelByName(perception.box_model());
      if (!dims.ok()) {
        return Invalid(absl::StrCat("perception.box_model: ", dims.status().message()));
      }
      p->box_model = perception.box_model();
      p->box = *dims;
      break;
    }
    case v1::PerceptionClientConfig::BOX_SIZE_NOT_SET:
      return Invalid("perception: set box { l b h } or box_model");
  }
  if (perception.has_reconnect_initial_s()) {
    p->reconnect_initial_s = perception.reconnect_initial_s();
  }
  if (perception.has_reconnect_max_s()) p->reconnect_max_s = perception.reconnect_max_s();
  p->allow_replay = perception.allow_replay();
  return absl::OkStatus();
}

absl::Status RobotFromProto(const v1::RobotConnectionConfig& robot, RobotConnectionOptions* r) {
  r->host = robot.host();
  // Ports beyond int's range still fail Validate() as out of range.
  auto port = [](uint32_t v) { return v > 65535u ? 65536 : static_cast<int>(v); };
  if (robot.has_dashboard_port()) r->dashboard_port = port(robot.dashboard_port());
  if (robot.has_primary_port()) r->primary_port = port(robot.primary_port());
  if (robot.has_rtde_port()) r->rtde_port = port(robot.rtde_port());
  if (!robot.arm_model().empty()) {
    absl::StatusOr<ur::ArmModel> model = ur::ParseArmModel(robot.arm_model());
    if (!model.ok()) return Invalid(absl::StrCat("robot.arm_model: ", model.status().message()));
    r->arm_model = *model;
  }
  if (robot.has_rtde_frequency_hz()) r->rtde_frequency_hz = robot.rtde_frequency_hz();
  if (robot.has_connect_timeout_s()) r->connect_timeout_s = robot.connect_timeout_s();
  if (robot.has_rtde_max_age_s()) r->rtde_max_age_s = robot.rtde_max_age_s();
  if (robot.has_read_timeout_s()) r->read_timeout_s = robot.read_timeout_s();
  if (robot.has_stop_confirm_timeout_s()) {
    r->stop_confirm_timeout_s = robot.stop_confirm_timeout_s();
  }
  r->bring_up_at_start = robot.bring_up_at_start();
  return absl::OkStatus();
}

absl::Status CellGeometryFromProto(const v1::RobotClientConfig& config,
                                   RobotClientOptions* options) {
  if (!config.has_base_pose_camera()) return Invalid("base_pose_camera is required");
  absl::StatusOr<Eigen::Isometry3d> base_T_camera =
      PoseFromProto(config.base_pose_camera(), "base_pose_camera");
  if (!base_T_camera.ok()) return base_T_camera.status();
  options->base_T_camera = *base_T_camera;

  if (!config.has_workspace()) return Invalid("workspace is required");
  options->workspace.min_m = Vector3dFromProto(config.workspace().min());
  options->workspace.max_m = Vector3dFromProto(config.workspace().max());
  return absl::OkStatus();
}

void SelectionFromProto(const v1::SelectionConfig& selection, SelectionOptions* options) {
  if (selection.has_max_grasp_tilt_deg()) {
    options->max_grasp_tilt_deg = selection.max_grasp_tilt_deg();
  }
  if (selection.has_min_score()) options->min_score = selection.min_score();
  if (selection.has_height_tie_m()) options->height_tie_m = selection.height_tie_m();
  if (selection.has_face_check_history()) {
    options->face_check_history = selection.face_check_history();
  }
}

absl::Status GripperFromProto(const v1::GripperConfig& gripper, GripperOptions* g) {
  if (gripper.has_tcp_offset()) {
    const Eigen::Vector3d position = Vector3dFromProto(gripper.tcp_offset().position());
    const Eigen::Vector3d rotation = Vector3dFromProto(gripper.tcp_offset().rotation_vector());
    if (!position.allFinite() || !rotation.allFinite()) {
      return Invalid("gripper.tcp_offset is not finite");
    }
    if (rotation.norm() > kPi + 1e-6) {
      return Invalid(absl::StrCat("gripper.tcp_offset.rotation_vector must have |r| <= pi, got ",
                                  rotation.norm()));
    }
    g->flange_T_tcp = ur::FromUrPose({position, rotation});
  }
  switch (gripper.suction_output()) {
    case v1::SUCTION_OUTPUT_KIND_UNSPECIFIED:
    case v1::SUCTION_OUTPUT_KIND_TOOL:
      g->suction_output = SuctionOutputKind::kTool;
      break;
    case v1::SUCTION_OUTPUT_KIND_STANDARD:
      g->suction_output = SuctionOutputKind::kStandard;
      break;
    default:
      return Invalid(
          absl::StrCat("gripper.suction_output: unknown kind ", gripper.suction_output()));
  }
  if (gripper.has_suction_output_index()) {
    g->suction_output_index =
        static_cast<int>(std::min<uint32_t>(gripper.suction_output_index(), 1000));
  }
  if (gripper.has_grasp_settle_s()) g->grasp_settle_s = gripper.grasp_settle_s();
  if (gripper.has_release_s()) g->release_s = gripper.release_s();
  return absl::OkStatus();
}

void WaypointsFromProto(const v1::WaypointConfig& waypoints, WaypointOptions* w) {
  if (waypoints.has_approach_distance_m()) w->approach_distance_m = waypoints.approach_distance_m();
  if (waypoints.has_retrieve_height_m()) w->retrieve_height_m = waypoints.retrieve_height_m();
  if (waypoints.has_place_approach_height_m()) {
    w->place_approach_height_m = waypoints.place_approach_height_m();
  }
}

absl::Status PlacePatternFromProto(const v1::PlacePatternConfig& pattern, double box_height_m,
                                   PlacePatternOptions* pp) {
  if (!pattern.has_origin()) return Invalid("place_pattern.origin is required");
  absl::StatusOr<Eigen::Isometry3d> origin =
      PoseFromProto(pattern.origin(), "place_pattern.origin");
  if (!origin.ok()) return origin.status();
  pp->base_T_origin = *origin;
  auto count = [](uint32_t v) { return static_cast<int>(std::min<uint32_t>(v, 1000000)); };
  if (pattern.has_rows()) pp->rows = count(pattern.rows());
  if (pattern.has_columns()) pp->columns = count(pattern.columns());
  if (pattern.has_layers()) pp->layers = count(pattern.layers());
  if (pattern.has_spacing_x_m()) pp->spacing_x_m = pattern.spacing_x_m();
  if (pattern.has_spacing_y_m()) pp->spacing_y_m = pattern.spacing_y_m();
  pp->layer_height_m = pattern.has_layer_height_m() ? pattern.layer_height_m() : box_height_m;
  return absl::OkStatus();
}

void MotionFromProto(const v1::MotionConfig& motion, MotionOptions* m) {
  if (motion.has_joint_speed_rad_s()) m->joint_speed_rad_s = motion.joint_speed_rad_s();
  if (motion.has_joint_acceleration_rad_s2()) {
    m->joint_acceleration_rad_s2 = motion.joint_acceleration_rad_s2();
  }
  if (motion.has_linear_speed_m_s()) m->linear_speed_m_s = motion.linear_speed_m_s();
  if (motion.has_linear_acceleration_m_s2()) {
    m->linear_acceleration_m_s2 = motion.linear_acceleration_m_s2();
  }
}

absl::Status RunFromProto(const v1::RobotClientConfig& config, RobotClientOptions* options) {
  if (config.clear_joints_rad_size() != 6) {
    return Invalid(absl::StrCat("clear_joints_rad must hold exactly 6 joint angles, got ",
                                config.clear_joints_rad_size()));
  }
  ur::Joints clear;
  for (int i = 0; i < 6; ++i) clear[i] = config.clear_joints_rad(i);
  options->clear_joints = clear;

  if (!config.status_listen_address().empty()) {
    options->status_listen_address = config.status_listen_address();
  }
  options->status_tls_cert = config.status_tls_cert();
  options->status_tls_key = config.status_tls_key();
  options->status_tls_client_ca = config.status_tls_client_ca();
  options->dry_run = config.dry_run();
  options->max_picks = static_cast<int>(std::min<uint32_t>(config.max_picks(), 1000000000u));
  return absl::OkStatus();
}

absl::StatusOr<RobotClientOptions> OptionsFromProto(const v1::RobotClientConfig& config) {
  RobotClientOptions options;
  for (absl::Status s :
       {PerceptionFromProto(config.perception(), &options.perception),
        RobotFromProto(config.robot(), &options.robot), CellGeometryFromProto(config, &options)}) {
    if (!s.ok()) return s;
  }
  SelectionFromProto(config.selection(), &options.selection);
  if (absl::Status s = GripperFromProto(config.gripper(), &options.gripper); !s.ok()) return s;
  WaypointsFromProto(config.waypoints(), &options.waypoints);
  if (absl::Status s = PlacePatternFromProto(config.place_pattern(), options.perception.box.h,
                                             &options.place_pattern);
      !s.ok()) {
    return s;
  }
  MotionFromProto(config.motion(), &options.motion);
  if (absl::Status s = RunFromProto(config, &options); !s.ok()) return s;
  return options;
}

}  // namespace cornerpose::robot_client
