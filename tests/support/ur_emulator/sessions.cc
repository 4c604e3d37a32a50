#include "tests/support/ur_emulator/sessions.h"

#include <cmath>

#include "absl/strings/ascii.h"
#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "absl/strings/strip.h"
#include "robot_client/ur/dashboard.h"
#include "robot_client/ur/primary.h"

namespace cornerpose::ur_emulator {
namespace {

constexpr const char* kControlWords[] = {"power on", "power off", "set robotmode run",
                                         "set unlock protective stop", "stop program"};

// The real controller's refusal (URSim 5.x).
constexpr char kUnlockRefused[] =
    "Cannot unlock protective stop until 5s after occurrence. Always inspect cause of "
    "protective stop before unlocking";

uint64_t Microseconds(double seconds) {
  return static_cast<uint64_t>(std::llround(std::max(0.0, seconds) * 1e6));
}

std::array<double, 6> PoseArray(const ur::UrPose& p) {
  return {p.position.x(), p.position.y(), p.position.z(),
          p.rotation.x(), p.rotation.y(), p.rotation.z()};
}

uint64_t OutputBits(const RobotSnapshot& s) {
  return static_cast<uint64_t>(s.standard_outputs & 0xff) |
         (static_cast<uint64_t>(s.configurable_outputs & 0xff) << 8) |
         (static_cast<uint64_t>(s.tool_outputs & 0x3) << 16);
}

ur::RtdeValue Zero(ur::RtdeType type) {
  switch (type) {
    case ur::RtdeType::kBool:
      return false;
    case ur::RtdeType::kUint8:
      return uint8_t{0};
    case ur::RtdeType::kUint32:
      return uint32_t{0};
    case ur::RtdeType::kUint64:
      return uint64_t{0};
    case ur::RtdeType::kInt32:
      return int32_t{0};
    case ur::RtdeType::kDouble:
      return 0.0;
    case ur::RtdeType::kVector3d:
      return std::array<double, 3>{};
    case ur::RtdeType::kVector6d:
      return std::array<double, 6>{};
    case ur::RtdeType::kVector6Int32:
      return std::array<int32_t, 6>{};
    case ur::RtdeType::kVector6Uint32:
      return std::array<uint32_t, 6>{};
  }
  return false;
}

}  // namespace

std::string DashboardReply(Controller& controller, absl::string_view command, bool* close) {
  *close = false;
  const std::string cmd(absl::StripAsciiWhitespace(command));
  const RobotSnapshot s = controller.Snapshot();
  if (cmd == "robotmode")
    return absl::StrCat("Robotmode: ", ur::RobotModeName(static_cast<ur::RobotMode>(s.robot_mode)));
  if (cmd == "safetymode")
    return absl::StrCat("Safetymode: ",
                        ur::SafetyModeName(static_cast<ur::SafetyMode>(s.safety_mode)));
  if (cmd == "safetystatus") {
    return absl::StrCat("Safetystatus: ",
                        ur::SafetyModeName(static_cast<ur::SafetyMode>(s.safety_mode)));
  }
  if (cmd == "running") {
    return absl::StrCat("Program running: ", s.program_running ? "true" : "false");
  }
  if (cmd == "programState") {
    return absl::StrCat(s.program_running ? "PLAYING " : "STOPPED ",
                        s.program_name.empty() ? "<unnamed>" : s.program_name);
  }
  if (cmd == "power on") {
    controller.PowerOn();
    return "Powering on";
  }
  if (cmd == "power off") {
    controller.PowerOff();
    return "Powering off";
  }
  if (cmd == "brake release") {
    controller.BrakeRelease();
    return "Brake releasing";
  }
  if (cmd == "unlock protective stop") {
    return controller.UnlockProtectiveStop() ? "Protective stop releasing" : kUnlockRefused;
  }
  if (cmd == "stop") return controller.StopProgram() ? "Stopped" : "Failed to execute: stop";
  // No .urp programs exist on the emulator.
  if (cmd == "play") return "Failed to execute: play";
  if (cmd == "pause") return "Failed to execute: pause";
  if (absl::StartsWith(cmd, "load ")) return absl::StrCat("File not found: ", cmd.substr(5));
  if (cmd == "get loaded program") return "No program loaded";
  if (cmd == "close safety popup") return "closing safety popup";
  if (cmd == "close popup") return "closing popup";
  if (cmd == "is in remote control") return "true";
  if (cmd == "get robot model") {
    return "UR5";  // UR5 and UR5e both answer UR5
  }
  if (cmd == "PolyscopeVersion") {
    const UrEmulatorOptions& o = controller.options();
    return absl::StrCat("URSoftware ", o.version_major, ".", o.version_minor, ".", o.version_bugfix,
                        ".", o.version_build, " (Sep 05 2021)");
  }
  if (cmd == "quit") {
    *close = true;
    return "Disconnected";
  }
  return absl::StrCat("could not understand: '", cmd, "'");
}

std::optional<PrimaryScriptAssembler::Item> PrimaryScriptAssembler::AddLine(
    absl::string_view line) {
  line = absl::StripSuffix(line, "\r");
  if (in_program_) {
    absl::StrAppend(&buffer_, line, "\n");
    if (absl::StripTrailingAsciiWhitespace(line) == "end") {
      in_program_ = false;
      return Item{false, std::move(buffer_)};
    }
    return std::nullopt;
  }
  const absl::string_view trimmed = absl::StripAsciiWhitespace(line);
  if (trimmed.empty()) return std::nullopt;
  for (const char* word : kControlWords) {
    if (trimmed == word) return Item{true, std::string(trimmed)};
  }
  if (absl::StartsWith(line, "def ") || absl::StartsWith(line, "sec ")) {
    in_program_ = true;
    buffer_ = absl::StrCat(line, "\n");
    return std::nullopt;
  }
  return Item{false, absl::StrCat(line, "\n")};
}

void ApplyPrimaryControlWord(Controller& controller, absl::string_view word) {
  if (word == "power on") {
    controller.PowerOn();
  } else if (word == "power off") {
    controller.PowerOff();
  } else if (word == "set robotmode run") {
    controller.BrakeRelease();
  } else if (word == "set unlock protective stop") {
    controller.UnlockProtectiveStop();
  } else if (word == "stop program") {
    controller.StopProgram();
  }
}

std::string EncodePrimaryVersion(const UrEmulatorOptions& options) {
  ur::VersionMessage m;
  m.project_name = "URControl";
  m.major = static_cast<uint8_t>(options.version_major);
  m.minor = static_cast<uint8_t>(options.version_minor);
  m.bugfix = options.version_bugfix;
  m.build = options.version_build;
  m.build_date = "05-09-2021, 10:23:58";
  return ur::EncodeVersionMessage(m);
}

std::string EncodePrimaryState(const RobotSnapshot& s) {
  ur::RobotState state;
  ur::RobotModeData mode;
  mode.timestamp = Microseconds(s.time_s);
  mode.power_on = s.robot_mode != kRobotModePowerOff;
  mode.protective_stopped = s.safety_mode == kSafetyModeProtectiveStop;
  mode.program_running = s.program_running;
  mode.robot_mode = static_cast<int8_t>(s.robot_mode);
  state.robot_mode = mode;

  ur::JointData joints;
  for (int i = 0; i < 6; ++i) {
    joints.joints[i].q_actual = s.joints[i];
    joints.joints[i].q_target = s.target_joints[i];
    joints.joints[i].qd_actual = s.joint_speeds[i];
    joints.joints[i].mode = s.robot_mode == kRobotModeRunning ? 253 : 236;  // 236: power off
  }
  state.joints = joints;

  ur::CartesianInfo cartesian;
  cartesian.tcp_pose = s.tcp;
  cartesian.tcp_offset = s.tcp_offset;
  state.cartesian = cartesian;

  ur::MasterboardData board;
  board.digital_output_bits = static_cast<uint32_t>(OutputBits(s));
  board.safety_mode = static_cast<uint8_t>(s.safety_mode);
  state.masterboard = board;
  return ur::EncodeRobotState(state);
}

std::string EncodePrimaryEvent(const ControllerEvent& event) {
  ur::RobotMessageHeader header;
  header.timestamp = Microseconds(event.time_s);
  switch (event.kind) {
    case ControllerEvent::Kind::kProgramStarted:
    case ControllerEvent::Kind::kProgramStopped: {
      ur::KeyMessage m;
      m.header = header;
      m.title = event.kind == ControllerEvent::Kind::kProgramStarted ? "PROGRAM_XXX_STARTED"
                                                                     : "PROGRAM_XXX_STOPPED";
      m.text = event.text;
      return ur::EncodeKeyMessage(m);
    }
    case ControllerEvent::Kind::kText: {
      ur::TextMessage m;
      m.header = header;
      m.text = event.text;
      return ur::EncodeTextMessage(m);
    }
    case ControllerEvent::Kind::kRuntimeException: {
      ur::RuntimeExceptionMessage m;
      m.header = header;
      m.line = event.line;
      m.column = event.column;
      m.text = event.text;
      return ur::EncodeRuntimeExceptionMessage(m);
    }
    case ControllerEvent::Kind::kSafetyMode: {
      ur::SafetyModeMessage m;
      m.header = header;
      m.safety_mode = static_cast<uint8_t>(event.safety_mode);
      return ur::EncodeSafetyModeMessage(m);
    }
  }
  return "";
}

ur::RtdeValue RtdeOutputValue(absl::string_view name, ur::RtdeType type, const RobotSnapshot& s) {
  auto joints = [](const ur::Joints& q) {
    std::array<double, 6> out;
    for (int i = 0; i < 6; ++i) out[i] = q[i];
    return out;
  };
  ur::RtdeValue value = Zero(type);
  if (name == "timestamp") {
    value = s.time_s;
  } else if (name == "actual_q") {
    value = joints(s.joints);
  } else if (name == "target_q") {
    value = joints(s.target_joints);
  } else if (name == "actual_qd") {
    value = joints(s.joint_speeds);
  } else if (name == "actual_TCP_pose") {
    value = PoseArray(s.tcp);
  } else if (name == "target_TCP_pose") {
    value = PoseArray(s.target_tcp);
  } else if (name == "tcp_offset") {
    value = PoseArray(s.tcp_offset);
  } else if (name == "actual_digital_output_bits") {
    value = OutputBits(s);
  } else if (name == "robot_mode") {
    value = int32_t{s.robot_mode};
  } else if (name == "safety_mode" || name == "safety_status") {
    value = int32_t{s.safety_mode};
  } else if (name == "joint_mode") {
    const int32_t mode = s.robot_mode == kRobotModeRunning ? 253 : 236;
    value = std::array<int32_t, 6>{mode, mode, mode, mode, mode, mode};
  } else if (name == "safety_status_bits") {
    uint32_t bits = 0;
    if (s.safety_mode == kSafetyModeNormal) bits |= 1u << 0;
    if (s.safety_mode == kSafetyModeProtectiveStop) bits |= 1u << 2;
    value = bits;
  } else if (name == "robot_status_bits") {
    uint32_t bits = 0;
    if (s.robot_mode != kRobotModePowerOff) bits |= 1u << 0;
    if (s.program_running) bits |= 1u << 1;
    value = bits;
  } else if (name == "runtime_state") {
    value = uint32_t{s.program_running ? 2u : 1u};
  } else if (name == "speed_scaling" || name == "target_speed_fraction") {
    value = 1.0;
  }
  // A value of another type than the table's would corrupt the package.
  if (ur::TypeOf(value) != type) value = Zero(type);
  return value;
}

std::string RtdeSession::Handle(const ur::RtdeFrame& frame) {
  using ur::RtdeMessageType;
  switch (static_cast<RtdeMessageType>(frame.type)) {
    case RtdeMessageType::kRequestProtocolVersion: {
      auto version = ur::ParseRequestProtocolVersion(frame.payload);
      const bool ok = version.ok() && (*version == 1 || *version == 2);
      if (ok) protocol_version_ = *version;
      return ur::EncodeAccepted(RtdeMessageType::kRequestProtocolVersion, ok);
    }
    case RtdeMessageType::kGetUrcontrolVersion: {
      ur::UrcontrolVersion v;
      v.major = options_.version_major;
      v.minor = options_.version_minor;
      v.bugfix = options_.version_bugfix;
      v.build = options_.version_build;
      return ur::EncodeUrcontrolVersion(v);
    }
    case RtdeMessageType::kSetupOutputs: {
      std::vector<std::string> names;
      double frequency = 125.0;
      if (protocol_version_ >= 2) {
        auto request = ur::ParseSetupOutputs(frame.payload);
        if (!request.ok()) {
          return ur::EncodeSetupReply(RtdeMessageType::kSetupOutputs, ur::SetupReply{});
        }
        names = request->names;
        frequency = request->frequency;
      } else {
        names = ur::ParseSetupInputs(frame.payload);
      }
      ur::SetupReply reply;
      std::vector<ur::RtdeType> types;
      bool all_found = !names.empty();
      for (const std::string& name : names) {
        auto type = ur::RtdeOutputType(name);
        if (type) {
          reply.types.push_back(ur::RtdeTypeName(*type));
          types.push_back(*type);
        } else {
          reply.types.push_back("NOT_FOUND");
          all_found = false;
        }
      }
      if (all_found && frequency > 0.0) {
        reply.recipe_id = next_recipe_id_++;
        output_recipe_id_ = reply.recipe_id;
        output_names_ = names;
        output_types_ = types;
        frequency_hz_ = std::min(frequency, options_.rtde_max_frequency_hz);
      }
      return ur::EncodeSetupReply(RtdeMessageType::kSetupOutputs, reply);
    }
    case RtdeMessageType::kSetupInputs: {
      const std::vector<std::string> names = ur::ParseSetupInputs(frame.payload);
      ur::SetupReply reply;
      bool all_found = !names.empty();
      for (const std::string& name : names) {
        auto type = ur::RtdeInputType(name);
        reply.types.push_back(type ? ur::RtdeTypeName(*type) : "NOT_FOUND");
        all_found &= type.has_value();
      }
      if (all_found) reply.recipe_id = next_recipe_id_++;
      return ur::EncodeSetupReply(RtdeMessageType::kSetupInputs, reply);
    }
    case RtdeMessageType::kStart:
      streaming_ = output_recipe_id_ != 0;
      return ur::EncodeAccepted(RtdeMessageType::kStart, streaming_);
    case RtdeMessageType::kPause:
      streaming_ = false;
      return ur::EncodeAccepted(RtdeMessageType::kPause, true);
    default:
      // Input data packages and client text messages change nothing here.
      return "";
  }
}

std::string RtdeSession::DataPackage(const RobotSnapshot& snapshot) const {
  ur::RtdeDataPackage package;
  package.recipe_id = output_recipe_id_;
  for (size_t i = 0; i < output_names_.size(); ++i) {
    package.values.push_back(RtdeOutputValue(output_names_[i], output_types_[i], snapshot));
  }
  std::string frame = ur::EncodeDataPackage(package);
  if (protocol_version_ < 2 && frame.size() >= 4) {
    // v1 data packages carry no recipe id.
    frame.erase(3, 1);
    frame[0] = static_cast<char>((frame.size() >> 8) & 0xff);
    frame[1] = static_cast<char>(frame.size() & 0xff);
  }
  return frame;
}

}  // namespace cornerpose::ur_emulator
