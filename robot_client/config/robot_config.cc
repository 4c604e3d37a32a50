#include "robot_client/config/robot_config.h"

#include <cmath>
#include <filesystem>
#include <string>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "common/config/text_proto_file.h"
#include "common/validation/range_check.h"
#include "cornerpose/v1/robot_client_config.pb.h"
#include "robot_client/config/robot_config_proto.h"

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
  if (absl::Status s = CheckRange("selection.height_tie_m", height_tie_m, 0.0, 1.0); !s.ok()) {
    return s;
  }
  if (absl::Status s = CheckRange("selection.max_overlap_m", max_overlap_m, 0.0, 1.0); !s.ok()) {
    return s;
  }
  if (absl::Status s = CheckRange("selection.layer_tolerance_m", layer_tolerance_m, 1e-4, 1.0);
      !s.ok()) {
    return s;
  }
  if (min_layer_for_face_check < 0 || min_layer_for_face_check > 1000) {
    return Invalid(absl::StrCat("selection.min_layer_for_face_check is ", min_layer_for_face_check,
                                "; must be in [0, 1000]"));
  }
  if (face_check_history < 0 || face_check_history > 100) {
    return Invalid(absl::StrCat("selection.face_check_history is ", face_check_history,
                                "; must be in [0, 100]"));
  }
  return absl::OkStatus();
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
  if (absl::Status s =
          CheckPositive("waypoints.place_approach_height_m", place_approach_height_m, 2.0);
      !s.ok()) {
    return s;
  }
  return CheckRange("waypoints.pile_clearance_m", pile_clearance_m, 0.0, 1.0);
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
  if (absl::Status s = CheckPositive("robot.rtde_max_age_s", robot.rtde_max_age_s, 10.0); !s.ok()) {
    return s;
  }
  if (absl::Status s = CheckPositive("robot.read_timeout_s", robot.read_timeout_s, 60.0); !s.ok()) {
    return s;
  }
  if (absl::Status s =
          CheckPositive("robot.stop_confirm_timeout_s", robot.stop_confirm_timeout_s, 60.0);
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
  absl::StatusOr<RobotClientOptions> options = OptionsFromProto(config);
  if (!options.ok()) return Invalid(absl::StrCat(path, ": ", options.status().message()));
  // TLS files are relative to the file's directory, as the server's are.
  const std::filesystem::path base = std::filesystem::path(path).parent_path();
  for (std::string* file :
       {&options->perception.tls_ca, &options->perception.tls_cert, &options->perception.tls_key,
        &options->status_tls_cert, &options->status_tls_key, &options->status_tls_client_ca}) {
    if (!file->empty() && std::filesystem::path(*file).is_relative()) {
      *file = (base / *file).lexically_normal().string();
    }
  }
  if (absl::Status s = options->Validate(); !s.ok()) {
    return Invalid(absl::StrCat(path, ": ", s.message()));
  }
  return options;
}

}  // namespace cornerpose::robot_client
