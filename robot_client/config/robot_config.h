// What the robot-cell daemon is configured with, as plain C++ (the daemon
// never sees the protobuf), and loading it from the configuration file
// (cornerpose.v1.RobotClientConfig in protobuf text format; see
// proto/cornerpose/v1/robot_client_config.proto and
// deploy/config/robot_client.textproto).
//
// Frames: base = the UR controller's base frame (z up), camera = the depth
// camera's optical frame, flange = the tool flange, tcp = the suction cup's
// tip (tool z out of the cup). Metres, radians, seconds unless a name says
// otherwise.
#pragma once

#include <Eigen/Geometry>
#include <optional>
#include <string>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "common/box/box_types.h"
#include "robot_client/ur/kinematics.h"
#include "robot_client/ur/pose.h"

namespace cornerpose::robot_client {

struct PerceptionClientOptions {
  // host:port of the perception service.
  std::string server_address = "localhost:50051";
  // The frame source to subscribe to; required.
  std::string source;
  // When non-empty, the built-in model the subscription names (box then
  // holds its size); empty: the subscription sends `box`.
  std::string box_model;
  // The size of the boxes, metres; required (every side > 0).
  BoxDims box;
  // Reconnection back-off: the first wait, doubled after each failure up to
  // the last. Seconds; 0 < initial <= max.
  double reconnect_initial_s = 0.5;
  double reconnect_max_s = 10.0;
  // TLS to the perception service (README, "TLS"): PEM files; tls_ca and/or
  // tls_cert + tls_key set = TLS, all empty = plaintext.
  std::string tls_ca;
  std::string tls_cert;
  std::string tls_key;
  std::string tls_server_name;
  // Pick from a replay of recorded frames (a source that is not live): its
  // boxes may not be there. Off: such frames are refused (STOPPED, with the
  // reason) unless dry_run. The emulator cell of the demo sets it.
  bool allow_replay = false;
};

struct RobotConnectionOptions {
  // Host name or address of the UR controller; required.
  std::string host;
  // TCP ports, 1..65535 (tests set the emulator's ports).
  int dashboard_port = 29999;
  int primary_port = 30001;
  int rtde_port = 30004;
  ur::ArmModel arm_model = ur::ArmModel::kUr5e;
  // RTDE output rate, hertz, in (0, 500]; 125 works on CB3 and e-Series.
  double rtde_frequency_hz = 125.0;
  // Each connection attempt and handshake, seconds; > 0.
  double connect_timeout_s = 5.0;
  // RTDE state older than this is never planned from nor starts a program
  // (the cell waits for a fresh one), seconds; in (0, 10]. A program already
  // running is stopped only when the link stays silent for read_timeout_s.
  double rtde_max_age_s = 0.1;
  // A primary / RTDE link silent this long is taken as lost, seconds; in
  // (0, 60].
  double read_timeout_s = 1.0;
  // Bring the arm up at start without an operator's acknowledgement.
  bool bring_up_at_start = false;
  // Wait for a program stopped through the dashboard to be reported
  // stopped, seconds; in (0, 60].
  double stop_confirm_timeout_s = 3.0;
};

// An axis-aligned box in the base frame. Every commanded TCP position must
// lie inside it. No default: an empty box (min == max) is invalid.
struct Workspace {
  Eigen::Vector3d min_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d max_m = Eigen::Vector3d::Zero();

  // Bounds included; false for a non-finite point.
  bool Contains(const Eigen::Vector3d& base_p) const;
  // INVALID_ARGUMENT unless every bound is finite and min < max on each axis.
  absl::Status Validate() const;
};

struct SelectionOptions {
  // Largest angle between the grasp face's outward normal and base +z,
  // degrees, in [0, 90].
  double max_grasp_tilt_deg = 30.0;
  // Lowest detection score accepted, in [0, 1].
  double min_score = 0.0;
  // Grasp points closer in height than this are equally high (the higher
  // score wins), metres; >= 0.
  double height_tie_m = 0.01;
  // Declines a box whose footprint (its extent in base x, y) overlaps
  // another detected box's of the same layer (tops within layer_tolerance_m)
  // by more than this in both x and y, metres; >= 0. Two boxes cannot share
  // space: one of the two is misplaced (a centre off along its length), so
  // both are declined until a later frame separates them.
  double max_overlap_m = 0.02;
  // Tops closer in height than this are one layer, metres; > 0.
  double layer_tolerance_m = 0.03;
  // In a frame of at least this many boxes, a box whose grasp face is a
  // different face of the box model (its size along the normal differs by
  // more than layer_tolerance_m from what two thirds of the boxes in view
  // have) is declined: the detector took the wrong face size, so the box's
  // bottom, and where it is put down, would be wrong. 0 = no such check.
  int min_layer_for_face_check = 3;
  // The grasp depths of this many of the last completed picks vote in the
  // face check beside the boxes in view, [0, 100]; 0 = the frame alone. A
  // pallet holds one box lying one way: with its history the cell still
  // tells a wrong face from the right one when only the last box or two of
  // a layer are in view. Leave 0 for heaps and bins, whose boxes lie every
  // way.
  int face_check_history = 0;

  absl::Status Validate() const;
};

enum class SuctionOutputKind {
  kTool,      // set_tool_digital_out(index, b), index 0..1
  kStandard,  // set_standard_digital_out(index, b), index 0..7
};

struct GripperOptions {
  // The TCP (suction cup tip, tool z out of the cup) in the flange frame.
  Eigen::Isometry3d flange_T_tcp = Eigen::Isometry3d::Identity();
  SuctionOutputKind suction_output = SuctionOutputKind::kTool;
  int suction_output_index = 0;
  // Wait after vacuum on at G before lifting, seconds; >= 0.
  double grasp_settle_s = 0.3;
  // Wait after vacuum off at F before leaving, seconds; >= 0.
  double release_s = 0.3;

  absl::Status Validate() const;
};

struct WaypointOptions {
  // d: M = G + d * base z, metres; > 0.
  double approach_distance_m = 0.10;
  // h: R = G + h * base z, metres; > 0 (clears the pile).
  double retrieve_height_m = 0.25;
  // place_above = F + this * base z, metres; > 0.
  double place_approach_height_m = 0.10;
  // Clearance above the pile, metres, in [0, 1]: when the frame's boxes give
  // the pile's top (the highest detected box top), M is at least this above
  // it and R lifts the held box's bottom at least this above it (d and h
  // above are the minimums).
  double pile_clearance_m = 0.05;

  absl::Status Validate() const;
};

// rows x columns x layers slots; slot k fills row-major within a layer
// (columns fastest), then layers upwards. See place_pattern.h.
struct PlacePatternOptions {
  // Slot 0: where the first box's bottom centre goes, and the slot frame
  // (z up out of the pallet; the box's longer top side along x).
  Eigen::Isometry3d base_T_origin = Eigen::Isometry3d::Identity();
  int rows = 1;     // along the origin's y axis; >= 1
  int columns = 1;  // along the origin's x axis; >= 1
  int layers = 1;   // along the origin's z axis; >= 1
  // Column and row pitch, metres; > 0 when there is more than one.
  double spacing_x_m = 0.0;
  double spacing_y_m = 0.0;
  // Layer pitch, metres; > 0. No default here: LoadRobotClientConfig sets
  // it to the box height when the file leaves it out.
  double layer_height_m = 0.0;

  int slot_count() const { return rows * columns * layers; }
  absl::Status Validate() const;
};

struct MotionOptions {
  // Free moves (movej): leading joint speed rad/s in (0, pi], acceleration
  // rad/s^2 in (0, 40].
  double joint_speed_rad_s = 1.05;
  double joint_acceleration_rad_s2 = 1.4;
  // Straight moves (movel): tool speed m/s in (0, 1], acceleration m/s^2 in
  // (0, 5].
  double linear_speed_m_s = 0.1;
  double linear_acceleration_m_s2 = 0.5;

  absl::Status Validate() const;
};

struct RobotClientOptions {
  PerceptionClientOptions perception;
  RobotConnectionOptions robot;
  // Hand-eye calibration: the camera's optical frame in the base frame.
  Eigen::Isometry3d base_T_camera = Eigen::Isometry3d::Identity();
  Workspace workspace;
  SelectionOptions selection;
  GripperOptions gripper;
  WaypointOptions waypoints;
  PlacePatternOptions place_pattern;
  MotionOptions motion;
  // Joint angles out of the camera's view, radians, each within +-2 pi;
  // required, and its TCP (FK * flange_T_tcp) must lie in the workspace.
  std::optional<ur::Joints> clear_joints;
  // host:port of the daemon's status service; port 0 picks a free port.
  // Loopback by default: the status service is for the cell's own computer
  // unless it is given TLS and a wider address.
  std::string status_listen_address = "127.0.0.1:50061";
  // TLS of the status service (PEM files): cert + key = TLS; client_ca
  // (needs both) = client certificates required. All empty = plaintext.
  std::string status_tls_cert;
  std::string status_tls_key;
  std::string status_tls_client_ca;
  // Log the programs instead of sending them.
  bool dry_run = false;
  // Stop after this many picks; 0 = until the place pattern is full.
  int max_picks = 0;

  // Every part's Validate() and the checks across parts (the clear pose's
  // TCP inside the workspace, a rigid base_T_camera). INVALID_ARGUMENT
  // naming the field, as in "workspace: min.x 0.5 >= max.x 0.2".
  absl::Status Validate() const;
};

// Reads, converts and validates the file at `path`. Fields left unset take
// the defaults above (layer_height_m: the box height); quaternions must be
// unit within 1e-3 and are normalised. NOT_FOUND when the file does not
// exist; INVALID_ARGUMENT naming the file for a syntax error or an unknown
// field (with the parser's line:column) or a bad value (naming the field).
absl::StatusOr<RobotClientOptions> LoadRobotClientConfig(const std::string& path);

}  // namespace cornerpose::robot_client
