#include "robot_client/ur/primary.h"

#include <algorithm>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "robot_client/ur/byte_io.h"

namespace cornerpose::ur {
namespace {

constexpr size_t kHeaderSize = 5;  // int32 length + uint8 type
constexpr uint8_t kCb2RobotModeBody = 24;
constexpr uint8_t kCb2MasterboardBody = 59;

// Writes `type`, then the body from `fill`, with an int32 length header
// covering all of it (used for packages and sub-packages alike).
template <typename F>
void PutFramed(ByteWriter& w, uint8_t type, F fill) {
  const size_t start = w.size();
  w.PutI32(0);
  w.PutU8(type);
  fill(w);
  w.PatchI32(start, static_cast<int32_t>(w.size() - start));
}

void PutPose(ByteWriter& w, const UrPose& p) {
  for (int i = 0; i < 3; ++i) w.PutDouble(p.position[i]);
  for (int i = 0; i < 3; ++i) w.PutDouble(p.rotation[i]);
}

UrPose GetPose(ByteReader& r) {
  UrPose p;
  for (int i = 0; i < 3; ++i) p.position[i] = r.GetDouble("pose");
  for (int i = 0; i < 3; ++i) p.rotation[i] = r.GetDouble("pose");
  return p;
}

// ---- ROBOT_STATE sub-packages ----

absl::StatusOr<RobotModeData> ParseRobotMode(absl::string_view body) {
  ByteReader r(body);
  RobotModeData m;
  m.timestamp = r.GetU64("robot mode timestamp");
  m.real_robot_connected = r.GetBool();
  m.real_robot_enabled = r.GetBool();
  m.power_on = r.GetBool();
  m.emergency_stopped = r.GetBool();
  m.protective_stopped = r.GetBool();
  m.program_running = r.GetBool();
  m.program_paused = r.GetBool();
  m.robot_mode = r.GetI8("robot mode");
  if (body.size() == kCb2RobotModeBody) {
    m.control_mode.reset();
    m.target_speed_fraction = r.GetDouble("speed fraction");
    m.speed_scaling.reset();
    m.target_speed_fraction_limit.reset();
  } else {
    m.control_mode = r.GetU8("control mode");
    m.target_speed_fraction = r.GetDouble("target speed fraction");
    m.speed_scaling = r.GetDouble("speed scaling");
    m.target_speed_fraction_limit = r.GetDouble("target speed fraction limit");
  }
  if (!r.ok()) return r.status();
  m.extra = std::string(r.Rest());
  return m;
}

void PutRobotMode(ByteWriter& w, const RobotModeData& m) {
  w.PutU64(m.timestamp);
  w.PutBool(m.real_robot_connected);
  w.PutBool(m.real_robot_enabled);
  w.PutBool(m.power_on);
  w.PutBool(m.emergency_stopped);
  w.PutBool(m.protective_stopped);
  w.PutBool(m.program_running);
  w.PutBool(m.program_paused);
  w.PutI8(m.robot_mode);
  if (m.control_mode.has_value()) {
    w.PutU8(*m.control_mode);
    w.PutDouble(m.target_speed_fraction);
    w.PutDouble(m.speed_scaling.value_or(1.0));
    w.PutDouble(m.target_speed_fraction_limit.value_or(1.0));
  } else {
    w.PutDouble(m.target_speed_fraction);
  }
  w.PutBytes(m.extra);
}

absl::StatusOr<JointData> ParseJoints(absl::string_view body) {
  ByteReader r(body);
  JointData d;
  for (JointState& j : d.joints) {
    j.q_actual = r.GetDouble("q actual");
    j.q_target = r.GetDouble("q target");
    j.qd_actual = r.GetDouble("qd actual");
    j.current = r.GetFloat();
    j.voltage = r.GetFloat();
    j.motor_temperature = r.GetFloat();
    j.micro_temperature = r.GetFloat();
    j.mode = r.GetU8("joint mode");
  }
  if (!r.ok()) return r.status();
  d.extra = std::string(r.Rest());
  return d;
}

void PutJoints(ByteWriter& w, const JointData& d) {
  for (const JointState& j : d.joints) {
    w.PutDouble(j.q_actual);
    w.PutDouble(j.q_target);
    w.PutDouble(j.qd_actual);
    w.PutFloat(j.current);
    w.PutFloat(j.voltage);
    w.PutFloat(j.motor_temperature);
    w.PutFloat(j.micro_temperature);
    w.PutU8(j.mode);
  }
  w.PutBytes(d.extra);
}

absl::StatusOr<CartesianInfo> ParseCartesian(absl::string_view body) {
  ByteReader r(body);
  CartesianInfo c;
  c.tcp_pose = GetPose(r);
  if (r.remaining() >= 48) {
    c.tcp_offset = GetPose(r);
  } else {
    c.tcp_offset.reset();
  }
  if (!r.ok()) return r.status();
  c.extra = std::string(r.Rest());
  return c;
}

void PutCartesian(ByteWriter& w, const CartesianInfo& c) {
  PutPose(w, c.tcp_pose);
  if (c.tcp_offset.has_value()) PutPose(w, *c.tcp_offset);
  w.PutBytes(c.extra);
}

absl::StatusOr<MasterboardData> ParseMasterboard(absl::string_view body) {
  ByteReader r(body);
  MasterboardData m;
  m.io_words_16bit = body.size() == kCb2MasterboardBody;
  if (m.io_words_16bit) {
    m.digital_input_bits = r.GetU16("digital inputs");
    m.digital_output_bits = r.GetU16("digital outputs");
  } else {
    m.digital_input_bits = r.GetU32("digital inputs");
    m.digital_output_bits = r.GetU32("digital outputs");
  }
  m.analog_input_range0 = r.GetI8();
  m.analog_input_range1 = r.GetI8();
  m.analog_input0 = r.GetDouble();
  m.analog_input1 = r.GetDouble();
  m.analog_output_domain0 = r.GetI8();
  m.analog_output_domain1 = r.GetI8();
  m.analog_output0 = r.GetDouble();
  m.analog_output1 = r.GetDouble();
  m.masterboard_temperature = r.GetFloat();
  m.robot_voltage_48v = r.GetFloat();
  m.robot_current = r.GetFloat();
  m.master_io_current = r.GetFloat();
  m.safety_mode = r.GetU8("safety mode");
  m.in_reduced_mode = r.GetU8();
  m.euromap67_installed = r.GetI8("euromap67 installed");
  if (!r.ok()) return r.status();
  m.extra = std::string(r.Rest());
  return m;
}

void PutMasterboard(ByteWriter& w, const MasterboardData& m) {
  if (m.io_words_16bit) {
    w.PutU16(static_cast<uint16_t>(m.digital_input_bits));
    w.PutU16(static_cast<uint16_t>(m.digital_output_bits));
  } else {
    w.PutU32(m.digital_input_bits);
    w.PutU32(m.digital_output_bits);
  }
  w.PutI8(m.analog_input_range0);
  w.PutI8(m.analog_input_range1);
  w.PutDouble(m.analog_input0);
  w.PutDouble(m.analog_input1);
  w.PutI8(m.analog_output_domain0);
  w.PutI8(m.analog_output_domain1);
  w.PutDouble(m.analog_output0);
  w.PutDouble(m.analog_output1);
  w.PutFloat(m.masterboard_temperature);
  w.PutFloat(m.robot_voltage_48v);
  w.PutFloat(m.robot_current);
  w.PutFloat(m.master_io_current);
  w.PutU8(m.safety_mode);
  w.PutU8(m.in_reduced_mode);
  w.PutI8(m.euromap67_installed);
  w.PutBytes(m.extra);
}

absl::Status WithContext(const absl::Status& s, absl::string_view what) {
  return absl::Status(s.code(), absl::StrCat(what, ": ", s.message()));
}

absl::StatusOr<RobotState> ParseRobotState(absl::string_view body) {
  RobotState state;
  ByteReader r(body);
  while (!r.empty()) {
    const size_t offset = r.position() + kHeaderSize;
    absl::StatusOr<int32_t> length = r.I32("sub-package length");
    if (!length.ok()) return length.status();
    if (*length < static_cast<int32_t>(kHeaderSize) ||
        static_cast<size_t>(*length) - 4 > r.remaining()) {
      return absl::InvalidArgumentError(absl::StrCat("ROBOT_STATE sub-package at offset ",
                                                     offset - kHeaderSize, " has length ", *length,
                                                     ", ", r.remaining() + 4, " left"));
    }
    const uint8_t type = *r.U8();
    const absl::string_view sub = *r.Bytes(static_cast<size_t>(*length) - kHeaderSize);
    const std::string where = absl::StrCat("ROBOT_STATE sub-package type ", type);
    // A second one of a decoded type would overwrite the first (found by
    // fuzz/ur_primary_fuzzer: the package no longer re-encoded to its bytes).
    const bool decoded = type == 0 || type == 1 || type == 3 || type == 4;
    if (decoded && std::find(state.order.begin(), state.order.end(), type) != state.order.end()) {
      return absl::InvalidArgumentError(absl::StrCat(where, " appears twice"));
    }
    state.order.push_back(type);
    switch (static_cast<RobotStateType>(type)) {
      case RobotStateType::kRobotModeData: {
        absl::StatusOr<RobotModeData> m = ParseRobotMode(sub);
        if (!m.ok()) return WithContext(m.status(), where);
        state.robot_mode = std::move(*m);
        break;
      }
      case RobotStateType::kJointData: {
        absl::StatusOr<JointData> j = ParseJoints(sub);
        if (!j.ok()) return WithContext(j.status(), where);
        state.joints = std::move(*j);
        break;
      }
      case RobotStateType::kCartesianInfo: {
        absl::StatusOr<CartesianInfo> c = ParseCartesian(sub);
        if (!c.ok()) return WithContext(c.status(), where);
        state.cartesian = std::move(*c);
        break;
      }
      case RobotStateType::kMasterboardData: {
        absl::StatusOr<MasterboardData> m = ParseMasterboard(sub);
        if (!m.ok()) return WithContext(m.status(), where);
        state.masterboard = std::move(*m);
        break;
      }
      default:
        state.other.push_back(RawSubPackage{type, std::string(sub)});
        break;
    }
  }
  return state;
}

// ---- ROBOT_MESSAGE ----

void PutMessageHeader(ByteWriter& w, const RobotMessageHeader& h, RobotMessageType type) {
  w.PutU64(h.timestamp);
  w.PutI8(h.source);
  w.PutU8(static_cast<uint8_t>(type));
}

template <typename F>
std::string EncodeMessage(const RobotMessageHeader& h, RobotMessageType type, F fill) {
  ByteWriter w;
  PutFramed(w, static_cast<uint8_t>(PrimaryPackageType::kRobotMessage), [&](ByteWriter& b) {
    PutMessageHeader(b, h, type);
    fill(b);
  });
  return w.Take();
}

absl::StatusOr<PrimaryPackage> ParseRobotMessage(absl::string_view body) {
  ByteReader r(body);
  RobotMessageHeader h;
  h.timestamp = r.GetU64("message timestamp");
  h.source = r.GetI8("message source");
  const uint8_t type = r.GetU8("message type");
  if (!r.ok()) return WithContext(r.status(), "ROBOT_MESSAGE");
  const std::string where = absl::StrCat("ROBOT_MESSAGE type ", type);
  switch (static_cast<RobotMessageType>(type)) {
    case RobotMessageType::kVersion: {
      VersionMessage m;
      m.header = h;
      const int8_t name_length = r.GetI8("project name length");
      if (name_length < 0) return absl::InvalidArgumentError(where + ": negative name length");
      m.project_name = r.GetBytes(static_cast<size_t>(name_length), "project name");
      m.major = r.GetU8("major version");
      m.minor = r.GetU8("minor version");
      m.bugfix = r.GetI32("bugfix version");
      m.build = r.GetI32("build number");
      if (!r.ok()) return WithContext(r.status(), where);
      m.build_date = std::string(r.Rest());
      return m;
    }
    case RobotMessageType::kText: {
      TextMessage m;
      m.header = h;
      m.text = std::string(r.Rest());
      return m;
    }
    case RobotMessageType::kKey: {
      KeyMessage m;
      m.header = h;
      m.code = r.GetI32("code");
      m.argument = r.GetI32("argument");
      const uint8_t title_length = r.GetU8("title length");
      m.title = r.GetBytes(title_length, "title");
      if (!r.ok()) return WithContext(r.status(), where);
      m.text = std::string(r.Rest());
      return m;
    }
    case RobotMessageType::kRuntimeException: {
      RuntimeExceptionMessage m;
      m.header = h;
      m.line = r.GetI32("line");
      m.column = r.GetI32("column");
      if (!r.ok()) return WithContext(r.status(), where);
      m.text = std::string(r.Rest());
      return m;
    }
    case RobotMessageType::kSafetyMode: {
      SafetyModeMessage m;
      m.header = h;
      m.code = r.GetI32("code");
      m.argument = r.GetI32("argument");
      m.safety_mode = r.GetU8("safety mode");
      m.report_data_type = r.GetU32("report data type");
      m.report_data = r.GetU32("report data");
      if (!r.ok()) return WithContext(r.status(), where);
      if (!r.empty()) {
        return absl::InvalidArgumentError(
            absl::StrCat(where, ": ", r.remaining(), " unexpected trailing bytes"));
      }
      return m;
    }
    case RobotMessageType::kErrorCode: {
      ErrorCodeMessage m;
      m.header = h;
      m.code = r.GetI32("code");
      m.argument = r.GetI32("argument");
      m.report_level = r.GetI32("report level");
      m.data_type = r.GetU32("data type");
      m.data = r.GetU32("data");
      if (!r.ok()) return WithContext(r.status(), where);
      m.text = std::string(r.Rest());
      return m;
    }
    default:
      return OtherRobotMessage{.header = h, .message_type = type, .body = std::string(r.Rest())};
  }
}

}  // namespace

Joints ActualJoints(const JointData& data) {
  Joints q{};
  for (int i = 0; i < 6; ++i) q[i] = data.joints[i].q_actual;
  return q;
}

Joints TargetJoints(const JointData& data) {
  Joints q{};
  for (int i = 0; i < 6; ++i) q[i] = data.joints[i].q_target;
  return q;
}

absl::StatusOr<PrimaryPackage> ParsePrimaryPackage(absl::string_view frame) {
  ByteReader r(frame);
  absl::StatusOr<int32_t> length = r.I32("package length");
  if (!length.ok()) return length.status();
  if (*length < static_cast<int32_t>(kHeaderSize) || static_cast<size_t>(*length) != frame.size()) {
    return absl::InvalidArgumentError(absl::StrCat("primary package length field ", *length,
                                                   " does not match its ", frame.size(), " bytes"));
  }
  const uint8_t type = *r.U8();
  const absl::string_view body = r.Rest();
  switch (static_cast<PrimaryPackageType>(type)) {
    case PrimaryPackageType::kRobotState: {
      absl::StatusOr<RobotState> state = ParseRobotState(body);
      if (!state.ok()) return state.status();
      return std::move(*state);
    }
    case PrimaryPackageType::kRobotMessage:
      return ParseRobotMessage(body);
    default:
      return OtherPackage{.type = type, .body = std::string(body)};
  }
}

std::string EncodeRobotState(const RobotState& state) {
  std::vector<uint8_t> order = state.order;
  if (order.empty()) {
    if (state.robot_mode) order.push_back(0);
    if (state.joints) order.push_back(1);
    if (state.cartesian) order.push_back(4);
    if (state.masterboard) order.push_back(3);
    for (const RawSubPackage& raw : state.other) order.push_back(raw.type);
  }
  std::vector<bool> used(state.other.size(), false);
  ByteWriter w;
  PutFramed(w, static_cast<uint8_t>(PrimaryPackageType::kRobotState), [&](ByteWriter& b) {
    for (uint8_t type : order) {
      switch (static_cast<RobotStateType>(type)) {
        case RobotStateType::kRobotModeData:
          if (state.robot_mode)
            PutFramed(b, type, [&](ByteWriter& s) { PutRobotMode(s, *state.robot_mode); });
          break;
        case RobotStateType::kJointData:
          if (state.joints) PutFramed(b, type, [&](ByteWriter& s) { PutJoints(s, *state.joints); });
          break;
        case RobotStateType::kCartesianInfo:
          if (state.cartesian)
            PutFramed(b, type, [&](ByteWriter& s) { PutCartesian(s, *state.cartesian); });
          break;
        case RobotStateType::kMasterboardData:
          if (state.masterboard)
            PutFramed(b, type, [&](ByteWriter& s) { PutMasterboard(s, *state.masterboard); });
          break;
        default:
          // The next unused raw sub-package of this type.
          for (size_t i = 0; i < state.other.size(); ++i) {
            if (!used[i] && state.other[i].type == type) {
              used[i] = true;
              PutFramed(b, type, [&](ByteWriter& s) { s.PutBytes(state.other[i].body); });
              break;
            }
          }
          break;
      }
    }
  });
  return w.Take();
}

std::string EncodeVersionMessage(const VersionMessage& m) {
  return EncodeMessage(m.header, RobotMessageType::kVersion, [&](ByteWriter& w) {
    const size_t n = std::min<size_t>(m.project_name.size(), 127);
    w.PutI8(static_cast<int8_t>(n));
    w.PutBytes(absl::string_view(m.project_name).substr(0, n));
    w.PutU8(m.major);
    w.PutU8(m.minor);
    w.PutI32(m.bugfix);
    w.PutI32(m.build);
    w.PutBytes(m.build_date);
  });
}

std::string EncodeTextMessage(const TextMessage& m) {
  return EncodeMessage(m.header, RobotMessageType::kText,
                       [&](ByteWriter& w) { w.PutBytes(m.text); });
}

std::string EncodeKeyMessage(const KeyMessage& m) {
  return EncodeMessage(m.header, RobotMessageType::kKey, [&](ByteWriter& w) {
    const size_t n = std::min<size_t>(m.title.size(), 255);
    w.PutI32(m.code);
    w.PutI32(m.argument);
    w.PutU8(static_cast<uint8_t>(n));
    w.PutBytes(absl::string_view(m.title).substr(0, n));
    w.PutBytes(m.text);
  });
}

std::string EncodeRuntimeExceptionMessage(const RuntimeExceptionMessage& m) {
  return EncodeMessage(m.header, RobotMessageType::kRuntimeException, [&](ByteWriter& w) {
    w.PutI32(m.line);
    w.PutI32(m.column);
    w.PutBytes(m.text);
  });
}

std::string EncodeSafetyModeMessage(const SafetyModeMessage& m) {
  return EncodeMessage(m.header, RobotMessageType::kSafetyMode, [&](ByteWriter& w) {
    w.PutI32(m.code);
    w.PutI32(m.argument);
    w.PutU8(m.safety_mode);
    w.PutU32(m.report_data_type);
    w.PutU32(m.report_data);
  });
}

std::string EncodeErrorCodeMessage(const ErrorCodeMessage& m) {
  return EncodeMessage(m.header, RobotMessageType::kErrorCode, [&](ByteWriter& w) {
    w.PutI32(m.code);
    w.PutI32(m.argument);
    w.PutI32(m.report_level);
    w.PutU32(m.data_type);
    w.PutU32(m.data);
    w.PutBytes(m.text);
  });
}

std::string EncodePrimaryPackage(const PrimaryPackage& package) {
  struct Visitor {
    std::string operator()(const RobotState& p) const { return EncodeRobotState(p); }
    std::string operator()(const VersionMessage& p) const { return EncodeVersionMessage(p); }
    std::string operator()(const TextMessage& p) const { return EncodeTextMessage(p); }
    std::string operator()(const KeyMessage& p) const { return EncodeKeyMessage(p); }
    std::string operator()(const RuntimeExceptionMessage& p) const {
      return EncodeRuntimeExceptionMessage(p);
    }
    std::string operator()(const SafetyModeMessage& p) const { return EncodeSafetyModeMessage(p); }
    std::string operator()(const ErrorCodeMessage& p) const { return EncodeErrorCodeMessage(p); }
    std::string operator()(const OtherRobotMessage& p) const {
      ByteWriter w;
      PutFramed(w, static_cast<uint8_t>(PrimaryPackageType::kRobotMessage), [&](ByteWriter& b) {
        b.PutU64(p.header.timestamp);
        b.PutI8(p.header.source);
        b.PutU8(p.message_type);
        b.PutBytes(p.body);
      });
      return w.Take();
    }
    std::string operator()(const OtherPackage& p) const {
      ByteWriter w;
      PutFramed(w, p.type, [&](ByteWriter& b) { b.PutBytes(p.body); });
      return w.Take();
    }
  };
  return std::visit(Visitor{}, package);
}

void PrimaryFramer::Append(absl::string_view bytes) { buffer_.append(bytes.data(), bytes.size()); }

absl::StatusOr<std::optional<std::string>> PrimaryFramer::Next() {
  if (buffer_.size() < 4) return std::nullopt;
  ByteReader r(buffer_);
  const int32_t length = *r.I32();
  if (length < static_cast<int32_t>(kHeaderSize) || static_cast<size_t>(length) > kMaxPackageSize) {
    return absl::DataLossError(
        absl::StrCat("primary stream out of step: package length field ", length));
  }
  if (buffer_.size() < static_cast<size_t>(length)) return std::nullopt;
  std::string package = buffer_.substr(0, static_cast<size_t>(length));
  buffer_.erase(0, static_cast<size_t>(length));
  return package;
}

}  // namespace cornerpose::ur
