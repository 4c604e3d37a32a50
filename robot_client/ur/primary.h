// The primary / secondary client interface (ports 30001 / 30002): framing,
// the ROBOT_STATE sub-packages a daemon needs, the robot messages that report
// program execution, and the matching encoders, so the controller emulator
// produces the same bytes a controller does. Layouts: URCL (see
// shared/design/ur-interface.md section 2.2), checked against the recorded
// packets in tests/data/ur.
//
// Every decoded struct keeps the bytes it does not interpret (`extra`, raw
// sub-packages), so Encode(Parse(bytes)) == bytes.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "robot_client/ur/pose.h"

namespace cornerpose::ur {

// Package types (the uint8 after the int32 length).
enum class PrimaryPackageType : uint8_t {
  kModbusInfo = 5,
  kRobotState = 16,
  kRobotMessage = 20,
  kHmc = 22,
  kProgramStateMessage = 25,
};

// ROBOT_STATE sub-package types.
enum class RobotStateType : uint8_t {
  kRobotModeData = 0,
  kJointData = 1,
  kToolData = 2,
  kMasterboardData = 3,
  kCartesianInfo = 4,
  kKinematicsInfo = 5,
  kConfigurationData = 6,
  kForceModeData = 7,
  kAdditionalInfo = 8,
  kCalibrationData = 9,
  kSafetyData = 10,
  kToolCommInfo = 11,
  kToolModeInfo = 12,
};

// ROBOT_MESSAGE message types.
enum class RobotMessageType : uint8_t {
  kText = 0,
  kProgramLabel = 1,
  kPopup = 2,
  kVersion = 3,
  kSafetyMode = 5,
  kErrorCode = 6,
  kKey = 7,
  kRequestValue = 9,
  kRuntimeException = 10,
};

// Sub-package 0. The defaults give the 5.x layout (47 bytes); a 29-byte
// CB2 (1.x) sub-package has no control mode, one speed fraction and no tail.
struct RobotModeData {
  uint64_t timestamp = 0;
  bool real_robot_connected = true;
  bool real_robot_enabled = true;
  bool power_on = true;
  bool emergency_stopped = false;
  bool protective_stopped = false;
  bool program_running = false;
  bool program_paused = false;
  int8_t robot_mode = 7;  // RobotMode, 7 = RUNNING (dashboard.h)
  // Absent in the CB2 layout.
  std::optional<uint8_t> control_mode = 0;
  double target_speed_fraction = 1.0;
  std::optional<double> speed_scaling = 1.0;
  std::optional<double> target_speed_fraction_limit = 1.0;
  std::string extra = std::string(1, '\0');  // 5.x: one reserved byte
};

// Sub-package 1: 41 bytes per joint.
struct JointState {
  double q_actual = 0.0;   // rad
  double q_target = 0.0;   // rad
  double qd_actual = 0.0;  // rad/s
  float current = 0.0f;    // A
  float voltage = 48.0f;   // V
  float motor_temperature = 25.0f;
  float micro_temperature = 25.0f;
  uint8_t mode = 253;  // 253 = running
};
struct JointData {
  std::array<JointState, 6> joints;
  std::string extra;
};
Joints ActualJoints(const JointData& data);
Joints TargetJoints(const JointData& data);

// Sub-package 4: TCP pose, and the TCP offset (3.2+; absent on CB2).
struct CartesianInfo {
  UrPose tcp_pose;
  std::optional<UrPose> tcp_offset = UrPose{};
  std::string extra;
};

// Sub-package 3. The defaults give the 5.x layout (75 bytes). CB2 (1.x)
// carries 16-bit IO words and its sub-package is 64 bytes; that length is
// how the layout is recognised.
struct MasterboardData {
  bool io_words_16bit = false;
  uint32_t digital_input_bits = 0;
  uint32_t digital_output_bits = 0;
  int8_t analog_input_range0 = 0;
  int8_t analog_input_range1 = 0;
  double analog_input0 = 0.0;
  double analog_input1 = 0.0;
  int8_t analog_output_domain0 = 0;
  int8_t analog_output_domain1 = 0;
  double analog_output0 = 0.0;
  double analog_output1 = 0.0;
  float masterboard_temperature = 25.0f;
  float robot_voltage_48v = 48.0f;
  float robot_current = 0.0f;
  float master_io_current = 0.0f;
  uint8_t safety_mode = 1;  // SafetyMode, 1 = NORMAL (CB2: master safety state)
  uint8_t in_reduced_mode = 0;
  int8_t euromap67_installed = 0;
  // 5.x: uint32 unused, uint8 operational mode selector input, uint8 three
  // position enabling device input, uint8 unused.
  std::string extra = std::string(7, '\0');
};

// A sub-package this library does not decode: its type and body.
struct RawSubPackage {
  uint8_t type = 0;
  std::string body;  // after the 5-byte header
};

struct RobotState {
  std::optional<RobotModeData> robot_mode;
  std::optional<JointData> joints;
  std::optional<CartesianInfo> cartesian;
  std::optional<MasterboardData> masterboard;
  std::vector<RawSubPackage> other;
  // Sub-package types in the order received, for byte-exact re-encoding;
  // empty: robot mode, joints, Cartesian, masterboard, then `other`.
  std::vector<uint8_t> order;
};

struct RobotMessageHeader {
  uint64_t timestamp = 0;
  int8_t source = -2;
};

struct VersionMessage {
  RobotMessageHeader header;
  std::string project_name = "URControl";
  uint8_t major = 5;
  uint8_t minor = 8;
  int32_t bugfix = 0;
  int32_t build = 0;
  std::string build_date;
};

struct TextMessage {
  RobotMessageHeader header;
  std::string text;
};

// KEY: program feedback uses titles PROGRAM_XXX_STARTED / _STOPPED with the
// program name as text.
struct KeyMessage {
  RobotMessageHeader header;
  int32_t code = 0;
  int32_t argument = 0;
  std::string title;
  std::string text;
};

struct RuntimeExceptionMessage {
  RobotMessageHeader header;
  int32_t line = 0;
  int32_t column = 0;
  std::string text;
};

struct SafetyModeMessage {
  RobotMessageHeader header;
  int32_t code = 0;
  int32_t argument = 0;
  uint8_t safety_mode = 1;  // SafetyMode
  uint32_t report_data_type = 0;
  uint32_t report_data = 0;  // raw 4 bytes (an int32 or float for some types)
};

struct ErrorCodeMessage {
  RobotMessageHeader header;
  int32_t code = 0;
  int32_t argument = 0;
  int32_t report_level = 0;  // 0 DEBUG .. 5 CRITICAL_FAULT
  uint32_t data_type = 0;
  uint32_t data = 0;
  std::string text;
};

// A robot message of another type (program label, popup, ...).
struct OtherRobotMessage {
  RobotMessageHeader header;
  uint8_t message_type = 0;
  std::string body;  // after the message type
};

// A package of another type (program state message, modbus, ...).
struct OtherPackage {
  uint8_t type = 0;
  std::string body;  // after the 5-byte header
};

using PrimaryPackage =
    std::variant<RobotState, VersionMessage, TextMessage, KeyMessage, RuntimeExceptionMessage,
                 SafetyModeMessage, ErrorCodeMessage, OtherRobotMessage, OtherPackage>;

// One complete package (int32 length first; the length must equal
// frame.size()). Unknown types are returned as Other*; truncated or
// inconsistent bytes give INVALID_ARGUMENT / OUT_OF_RANGE, never a crash.
absl::StatusOr<PrimaryPackage> ParsePrimaryPackage(absl::string_view frame);

// Complete packages (length header included).
std::string EncodePrimaryPackage(const PrimaryPackage& package);
std::string EncodeRobotState(const RobotState& state);
std::string EncodeVersionMessage(const VersionMessage& m);
std::string EncodeTextMessage(const TextMessage& m);
std::string EncodeKeyMessage(const KeyMessage& m);
std::string EncodeRuntimeExceptionMessage(const RuntimeExceptionMessage& m);
std::string EncodeSafetyModeMessage(const SafetyModeMessage& m);
std::string EncodeErrorCodeMessage(const ErrorCodeMessage& m);

// Splits a TCP byte stream into packages, whatever the read boundaries.
class PrimaryFramer {
 public:
  // Packages longer than this are taken as a lost stream position.
  static constexpr size_t kMaxPackageSize = 1 << 20;

  void Append(absl::string_view bytes);
  // The next complete package, nullopt when more bytes are needed;
  // DATA_LOSS when the length field is impossible (< 5 or too large): the
  // stream cannot be resynchronised and should be closed.
  absl::StatusOr<std::optional<std::string>> Next();
  size_t buffered() const { return buffer_.size(); }

 private:
  std::string buffer_;
};

}  // namespace cornerpose::ur
