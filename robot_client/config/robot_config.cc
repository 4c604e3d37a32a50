#include "robot_client/config/robot_config.h"

#include <cmath>
#include <string>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "common/box/box_models.h"
#include "common/config/text_proto_file.h"
#include "common/validation/range_check.h"
#include "common/wire/geometry_wire.h"
#include "cornerpose/v1/robot_client_config.pb.h"

namespace cornerpose::robot_client {
namespace {

constexpr double kPi = 3.14159265358979323846;

absl::Status Invalid(absl::string_view message) { return absl::InvalidArgumentError(message); }

absl::Status CheckPort(absl::string_view field, int port) {
  return CheckRange(field, port, 1, 65535);
}

absl::Status CheckRigid(absl::string_view field, const Eigen::Isometry3d& T) {
  if (!T.matrix().allFinite()) return Invalid(absl::StrCat(field, " is not finite"));
  const Eigen::Matrix3d R = T.linear();
  if ((R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() > 1e-6 ||
      std::abs(R.determinant() - 1.0) > 1e-6) {
    return Invalid(absl::StrCat(field, " has no proper rotation"));
  }
  return absl::OkStatus();
}

std::string Xyz(const Eigen::Vector3d& p) {
  return absl::StrFormat("(%.4f, %.4f, %.4f)", p.x(), p.y(), p.z());
}

using wire::PoseFromProto;
using wire::Vector3dFromProto;

absl::StatusOr<RobotClientOptions> FromProto(const v1::RobotClientConfig& config) {
  RobotClientOptions options;

  // perception
  const v1::PerceptionClientConfig& perception = config.perception();
  PerceptionClientOptions& p = options.perception;
  if (!perception.server_address().empty()) p.server_address = perception.server_address();
  p.source = perception.source();
  switch (perception.box_size_case()) {
    case v1::PerceptionClientConfig::kBox:
      p.box = {perception.box().l(), perception.box().b(), perception.box().h()};
      break;
    case v1::PerceptionClientConfig::kBoxModel: {
      absl::StatusOr<BoxDims> dims = BoxModelByName(perception.box_model());
      if (!dims.ok())
        return Invalid(absl::StrCat("perception.box_model: ", dims.status().message()));
      p.box_model = perception.box_model();
      p.box = *dims;
      break;
    }
    case v1::PerceptionClientConfig::BOX_SIZE_NOT_SET:
      return Invalid("perception: set box { l b h } or box_model");
  }
  if (perception.has_reconnect_initial_s())
    p.reconnect_initial_s = perception.reconnect_initial_s();
  if (perception.has_reconnect_max_s()) p.reconnect_max_s = perception.reconnect_max_s();

  // robot
  const v1::RobotConnectionConfig& robot = config.robot();
  RobotConnectionOptions& r = options.robot;
  r.host = robot.host();
  // Ports beyond int's range still fail Validate() as out of range.
  auto port = [](uint32_t v) { return v > 65535u ? 65536 : static_cast<int>(v); };
  if (robot.has_dashboard_port()) r.dashboard_port = port(robot.dashboard_port());
  if (robot.has_primary_port()) r.primary_port = port(robot.primary_port());
  if (robot.has_rtde_port()) r.rtde_port = port(robot.rtde_port());
  if (!robot.arm_model().empty()) {
    absl::StatusOr<ur::ArmModel> model = ur::ParseArmModel(robot.arm_model());
    if (!model.ok()) return Invalid(absl::StrCat("robot.arm_model: ", model.status().message()));
    r.arm_model = *model;
  }
  if (robot.has_rtde_frequency_hz()) r.rtde_frequency_hz = robot.rtde_frequency_hz();
  if (robot.has_connect_timeout_s()) r.connect_timeout_s = robot.connect_timeout_s();

  // base_pose_camera
  if (!config.has_base_pose_camera()) return Invalid("base_pose_camera is required");
  absl::StatusOr<Eigen::Isometry3d> base_T_camera =
      PoseFromProto(config.base_pose_camera(), "base_pose_camera");
  if (!base_T_camera.ok()) return base_T_camera.status();
  options.base_T_camera = *base_T_camera;

  // workspace
  if (!config.has_workspace()) return Invalid("workspace is required");
  options.workspace.min_m = Vector3dFromProto(config.workspace().min());
  options.workspace.max_m = Vector3dFromProto(config.workspace().max());

  // selection
  const v1::SelectionConfig& selection = config.selection();
  if (selection.has_max_grasp_tilt_deg()) {
    options.selection.max_grasp_tilt_deg = selection.max_grasp_tilt_deg();
  }
  if (selection.has_min_score()) options.selection.min_score = selection.min_score();
  if (selection.has_height_tie_m()) options.selection.height_tie_m = selection.height_tie_m();

  // gripper
  const v1::GripperConfig& gripper = config.gripper();
  GripperOptions& g = options.gripper;
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
    g.flange_T_tcp = ur::FromUrPose({position, rotation});
  }
  switch (gripper.suction_output()) {
    case v1::SUCTION_OUTPUT_KIND_UNSPECIFIED:
    case v1::SUCTION_OUTPUT_KIND_TOOL:
      g.suction_output = SuctionOutputKind::kTool;
      break;
    case v1::SUCTION_OUTPUT_KIND_STANDARD:
      g.suction_output = SuctionOutputKind::kStandard;
      break;
    default:
      return Invalid(
          absl::StrCat("gripper.suction_output: unknown kind ", gripper.suction_output()));
  }
  if (gripper.has_suction_output_index()) {
    g.suction_output_index =
        static_cast<int>(std::min<uint32_t>(gripper.suction_output_index(), 1000));
  }
  if (gripper.has_grasp_settle_s()) g.grasp_settle_s = gripper.grasp_settle_s();
  if (gripper.has_release_s()) g.release_s = gripper.release_s();

  // waypoints
  const v1::WaypointConfig& waypoints = config.waypoints();
  WaypointOptions& w = options.waypoints;
  if (waypoints.has_approach_distance_m()) w.approach_distance_m = waypoints.approach_distance_m();
  if (waypoints.has_retrieve_height_m()) w.retrieve_height_m = waypoints.retrieve_height_m();
  if (waypoints.has_place_approach_height_m()) {
    w.place_approach_height_m = waypoints.place_approach_height_m();
  }

  // place_pattern
  const v1::PlacePatternConfig& pattern = config.place_pattern();
  PlacePatternOptions& pp = options.place_pattern;
  if (!pattern.has_origin()) return Invalid("place_pattern.origin is required");
  absl::StatusOr<Eigen::Isometry3d> origin =
      PoseFromProto(pattern.origin(), "place_pattern.origin");
  if (!origin.ok()) return origin.status();
  pp.base_T_origin = *origin;
  auto count = [](uint32_t v) { return static_cast<int>(std::min<uint32_t>(v, 1000000)); };
  if (pattern.has_rows()) pp.rows = count(pattern.rows());
  if (pattern.has_columns()) pp.columns = count(pattern.columns());
  if (pattern.has_layers()) pp.layers = count(pattern.layers());
  if (pattern.has_spacing_x_m()) pp.spacing_x_m = pattern.spacing_x_m();
  if (pattern.has_spacing_y_m()) pp.spacing_y_m = pattern.spacing_y_m();
  pp.layer_height_m = pattern.has_layer_height_m() ? pattern.layer_height_m() : p.box.h;

  // motion
  const v1::MotionConfig& motion = config.motion();
  MotionOptions& m = options.motion;
  if (motion.has_joint_speed_rad_s()) m.joint_speed_rad_s = motion.joint_speed_rad_s();
  if (motion.has_joint_acceleration_rad_s2()) {
    m.joint_acceleration_rad_s2 = motion.joint_acceleration_rad_s2();
  }
  if (motion.has_linear_speed_m_s()) m.linear_speed_m_s = motion.linear_speed_m_s();
  if (motion.has_linear_acceleration_m_s2()) {
    m.linear_acceleration_m_s2 = motion.linear_acceleration_m_s2();
  }

  // clear pose
  if (config.clear_joints_rad_size() != 6) {
    return Invalid(absl::StrCat("clear_joints_rad must hold exactly 6 joint angles, got ",
                                config.clear_joints_rad_size()));
  }
  ur::Joints clear;
  for (int i = 0; i < 6; ++i) clear[i] = config.clear_joints_rad(i);
  options.clear_joints = clear;

  if (!config.status_listen_address().empty()) {
    options.status_listen_address = config.status_listen_address();
  }
  options.dry_run = config.dry_run();
  options.max_picks = static_cast<int>(std::min<uint32_t>(config.max_picks(), 1000000000u));
  return options;
}

}  // namespace

bool Workspace::Contains(const Eigen::Vector3d& base_p) const {
  return base_p.allFinite() && (base_p.array() >= min_m.array()).all() &&
         (base_p.array() <= max_m.array()).all();
}

absl::Status Workspace::Validate() const {
  if (!min_m.allFinite() || !max_m.allFinite()) return Invalid("workspace: bounds must be finite");
  static constexpr const char* kAxis[3] = {"x", "y", "z"};
  for (int i = 0; i < 3; ++i) {
    if (!(min_m[i] < max_m[i])) {
      return Invalid(absl::StrCat("workspace is empty: min.", kAxis[i], " ", min_m[i], " >= max.",
                                  kAxis[i], " ", max_m[i]));
    }
  }
  return absl::OkStatus();
}

absl::Status SelectionOptions::Validate() const {
  if (absl::Status s = CheckRange("selection.max_grasp_tilt_deg", max_grasp_tilt_deg, 0.0, 90.0);
      !s.ok()) {
    return s;
  }
  if (absl::Status s = CheckRange("selection.min_score", min_score, 0.0, 1.0); !s.ok()) return s;
  return CheckRange("selection.height_tie_m", height_tie_m, 0.0, 1.0);
}

absl::Status GripperOptions::Validate() const {
  if (absl::Status s = CheckRigid("gripper.tcp_offset", flange_T_tcp); !s.ok()) return s;
  if (flange_T_tcp.translation().norm() > 1.0) {
    return Invalid(absl::StrCat("gripper.tcp_offset is ", flange_T_tcp.translation().norm(),
                                " m from the flange; at most 1 m"));
  }
  // Tool outputs 0..1, standard outputs 0..7.
  const int max_index = suction_output == SuctionOutputKind::kTool ? 1 : 7;
  if (absl::Status s =
          CheckRange("gripper.suction_output_index", suction_output_index, 0, max_index);
      !s.ok()) {
    return s;
  }
  if (absl::Status s = CheckRange("gripper.grasp_settle_s", grasp_settle_s, 0.0, 60.0); !s.ok()) {
    return s;
  }
  return CheckRange("gripper.release_s", release_s, 0.0, 60.0);
}

absl::Status WaypointOptions::Validate() const {
  if (absl::Status s = CheckPositive("waypoints.approach_distance_m", approach_distance_m, 2.0);
      !s.ok()) {
    return s;
  }
  if (absl::Status s = CheckPositive("waypoints.retrieve_height_m", retrieve_height_m, 2.0);
      !s.ok()) {
    return s;
  }
  return CheckPositive("waypoints.place_approach_height_m", place_approach_height_m, 2.0);
}

absl::Status PlacePatternOptions::Validate() const {
  if (absl::Status s = CheckRigid("place_pattern.origin", base_T_origin); !s.ok()) return s;
  if (rows < 1 || columns < 1 || layers < 1) {
    return Invalid(absl::StrCat("place_pattern has no slots: rows ", rows, " x columns ", columns,
                                " x layers ", layers, "; each must be >= 1"));
  }
  if (static_cast<long long>(rows) * columns * layers > 1000000) {
    return Invalid("place_pattern: more than 1000000 slots");
  }
  if (columns > 1) {
    if (absl::Status s =
            CheckPositive("place_pattern.spacing_x_m (columns > 1)", spacing_x_m, 10.0);
        !s.ok()) {
      return s;
    }
  }
  if (rows > 1) {
    if (absl::Status s = CheckPositive("place_pattern.spacing_y_m (rows > 1)", spacing_y_m, 10.0);
        !s.ok()) {
      return s;
    }
  }
  return CheckPositive("place_pattern.layer_height_m", layer_height_m, 10.0);
}

absl::Status MotionOptions::Validate() const {
  if (absl::Status s = CheckPositive("motion.joint_speed_rad_s", joint_speed_rad_s, kPi); !s.ok()) {
    return s;
  }
  if (absl::Status s =
          CheckPositive("motion.joint_acceleration_rad_s2", joint_acceleration_rad_s2, 40.0);
      !s.ok()) {
    return s;
  }
  if (absl::Status s = CheckPositive("motion.linear_speed_m_s", linear_speed_m_s, 1.0); !s.ok()) {
    return s;
  }
  return CheckPositive("motion.linear_acceleration_m_s2", linear_acceleration_m_s2, 5.0);
}

absl::Status RobotClientOptions::Validate() const {
  // perception
  if (perception.server_address.empty()) return Invalid("perception.server_address is empty");
  if (perception.source.empty()) return Invalid("perception.source is required");
  if (absl::Status s = perception.box.Validate(); !s.ok()) {
    return Invalid(absl::StrCat("perception.box: ", s.message()));
  }
  if (absl::Status s =
          CheckPositive("perception.reconnect_initial_s", perception.reconnect_initial_s, 3600.0);
      !s.ok()) {
    return s;
  }
  // At least the first wait (reconnect_initial_s).
  if (absl::Status s = CheckRange("perception.reconnect_max_s", perception.reconnect_max_s,
                                  perception.reconnect_initial_s, 3600.0);
      !s.ok()) {
    return s;
  }
  // robot
  if (robot.host.empty()) return Invalid("robot.host is required");
  if (absl::Status s = CheckPort("robot.dashboard_port", robot.dashboard_port); !s.ok()) return s;
  if (absl::Status s = CheckPort("robot.primary_port", robot.primary_port); !s.ok()) return s;
  if (absl::Status s = CheckPort("robot.rtde_port", robot.rtde_port); !s.ok()) return s;
  if (absl::Status s = CheckPositive("robot.rtde_frequency_hz", robot.rtde_frequency_hz, 500.0);
      !s.ok()) {
    return s;
  }
  if (absl::Status s = CheckPositive("robot.connect_timeout_s", robot.connect_timeout_s, 600.0);
      !s.ok()) {
    return s;
  }
  if (absl::Status s = CheckRigid("base_pose_camera", base_T_camera); !s.ok()) return s;
  for (absl::Status s : {workspace.Validate(), selection.Validate(), gripper.Validate(),
                         waypoints.Validate(), place_pattern.Validate(), motion.Validate()}) {
    if (!s.ok()) return s;
  }
  // clear pose
  if (!clear_joints.has_value()) return Invalid("clear_joints_rad is required");
  for (int i = 0; i < 6; ++i) {
    if (absl::Status s = CheckRange(absl::StrCat("clear_joints_rad[", i, "]"), (*clear_joints)[i],
                                    -2.0 * kPi, 2.0 * kPi);
        !s.ok()) {
      return s;
    }
  }
  const Eigen::Vector3d clear_tcp =
      (ur::ForwardKinematics(robot.arm_model, *clear_joints) * gripper.flange_T_tcp).translation();
  if (!workspace.Contains(clear_tcp)) {
    return Invalid(absl::StrCat("clear_joints_rad put the TCP at ", Xyz(clear_tcp),
                                ", outside the workspace ", Xyz(workspace.min_m), " .. ",
                                Xyz(workspace.max_m)));
  }
  if (status_listen_address.empty()) return Invalid("status_listen_address is empty");
  if (absl::Status s = CheckAtLeast("max_picks", max_picks, 0.0); !s.ok()) return s;
  return absl::OkStatus();
}

absl::StatusOr<RobotClientOptions> LoadRobotClientConfig(const std::string& path) {
  v1::RobotClientConfig config;
  if (absl::Status s = ReadTextProtoFile(path, &config); !s.ok()) return s;
  absl::StatusOr<RobotClientOptions> options = FromProto(config);
  if (!options.ok()) return Invalid(absl::StrCat(path, ": ", options.status().message()));
  if (absl::Status s = options->Validate(); !s.ok()) {
    return Invalid(absl::StrCat(path, ": ", s.message()));
  }
  return options;
}

}  // namespace cornerpose::robot_client
