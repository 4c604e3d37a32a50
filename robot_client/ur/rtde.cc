#include "robot_client/ur/rtde.h"

#include <algorithm>
#include <limits>

#include "absl/status/status.h"
#include "absl/strings/ascii.h"
#include "absl/strings/match.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_split.h"
#include "absl/strings/strip.h"
#include "robot_client/ur/byte_io.h"

namespace cornerpose::ur {
namespace {

constexpr size_t kHeaderSize = 3;  // uint16 size + uint8 type

struct TypeInfo {
  RtdeType type;
  const char* name;
  size_t size;
};
constexpr TypeInfo kTypes[] = {
    {RtdeType::kBool, "BOOL", 1},
    {RtdeType::kUint8, "UINT8", 1},
    {RtdeType::kUint32, "UINT32", 4},
    {RtdeType::kUint64, "UINT64", 8},
    {RtdeType::kInt32, "INT32", 4},
    {RtdeType::kDouble, "DOUBLE", 8},
    {RtdeType::kVector3d, "VECTOR3D", 24},
    {RtdeType::kVector6d, "VECTOR6D", 48},
    {RtdeType::kVector6Int32, "VECTOR6INT32", 24},
    {RtdeType::kVector6Uint32, "VECTOR6UINT32", 24},
};

struct Variable {
  const char* name;
  RtdeType type;
};
// URCL src/rtde/data_package.cpp (g_rtde_output_recipe_types).
constexpr Variable kOutputs[] = {
    {"timestamp", RtdeType::kDouble},
    {"target_q", RtdeType::kVector6d},
    {"target_qd", RtdeType::kVector6d},
    {"target_qdd", RtdeType::kVector6d},
    {"target_current", RtdeType::kVector6d},
    {"target_moment", RtdeType::kVector6d},
    {"actual_q", RtdeType::kVector6d},
    {"actual_qd", RtdeType::kVector6d},
    {"actual_current", RtdeType::kVector6d},
    {"joint_control_output", RtdeType::kVector6d},
    {"actual_TCP_pose", RtdeType::kVector6d},
    {"actual_TCP_speed", RtdeType::kVector6d},
    {"actual_TCP_force", RtdeType::kVector6d},
    {"target_TCP_pose", RtdeType::kVector6d},
    {"target_TCP_speed", RtdeType::kVector6d},
    {"actual_digital_input_bits", RtdeType::kUint64},
    {"joint_temperatures", RtdeType::kVector6d},
    {"actual_execution_time", RtdeType::kDouble},
    {"robot_mode", RtdeType::kInt32},
    {"joint_mode", RtdeType::kVector6Int32},
    {"safety_mode", RtdeType::kInt32},
    {"safety_status", RtdeType::kInt32},
    {"actual_tool_accelerometer", RtdeType::kVector3d},
    {"speed_scaling", RtdeType::kDouble},
    {"target_speed_fraction", RtdeType::kDouble},
    {"actual_momentum", RtdeType::kDouble},
    {"actual_main_voltage", RtdeType::kDouble},
    {"actual_robot_voltage", RtdeType::kDouble},
    {"actual_robot_current", RtdeType::kDouble},
    {"actual_joint_voltage", RtdeType::kVector6d},
    {"actual_digital_output_bits", RtdeType::kUint64},
    {"runtime_state", RtdeType::kUint32},
    {"elbow_position", RtdeType::kVector3d},
    {"elbow_velocity", RtdeType::kVector3d},
    {"robot_status_bits", RtdeType::kUint32},
    {"safety_status_bits", RtdeType::kUint32},
    {"analog_io_types", RtdeType::kUint32},
    {"standard_analog_input0", RtdeType::kDouble},
    {"standard_analog_input1", RtdeType::kDouble},
    {"standard_analog_output0", RtdeType::kDouble},
    {"standard_analog_output1", RtdeType::kDouble},
    {"io_current", RtdeType::kDouble},
    {"tool_analog_input0", RtdeType::kDouble},
    {"tool_analog_input1", RtdeType::kDouble},
    {"tool_output_voltage", RtdeType::kInt32},
    {"tool_output_current", RtdeType::kDouble},
    {"tool_temperature", RtdeType::kDouble},
    {"tcp_force_scalar", RtdeType::kDouble},
    {"tcp_offset", RtdeType::kVector6d},
    {"output_bit_registers0_to_31", RtdeType::kUint32},
    {"output_bit_registers32_to_63", RtdeType::kUint32},
};
constexpr Variable kInputs[] = {
    {"speed_slider_mask", RtdeType::kUint32},
    {"speed_slider_fraction", RtdeType::kDouble},
    {"standard_digital_output_mask", RtdeType::kUint8},
    {"standard_digital_output", RtdeType::kUint8},
    {"configurable_digital_output_mask", RtdeType::kUint8},
    {"configurable_digital_output", RtdeType::kUint8},
    {"tool_digital_output_mask", RtdeType::kUint8},
    {"tool_digital_output", RtdeType::kUint8},
    {"input_bit_registers0_to_31", RtdeType::kUint32},
    {"input_bit_registers32_to_63", RtdeType::kUint32},
};

// "<prefix>N" with N in 0..47.
bool IsRegister(absl::string_view name, absl::string_view prefix) {
  if (!absl::ConsumePrefix(&name, prefix) || name.empty() || name.size() > 2) return false;
  int n = 0;
  return absl::SimpleAtoi(name, &n) && n >= 0 && n <= 47 && absl::StrCat(n) == name;
}

std::vector<std::string> SplitNames(absl::string_view text) {
  if (text.empty()) return {};
  return absl::StrSplit(text, ',');
}

absl::Status ExpectEnd(const ByteReader& r, absl::string_view what) {
  if (!r.empty()) {
    return absl::InvalidArgumentError(
        absl::StrCat(what, ": ", r.remaining(), " unexpected trailing bytes"));
  }
  return absl::OkStatus();
}

}  // namespace

const char* RtdeTypeName(RtdeType type) {
  for (const TypeInfo& t : kTypes) {
    if (t.type == type) return t.name;
  }
  return "UNKNOWN";
}

absl::StatusOr<RtdeType> ParseRtdeTypeName(absl::string_view name) {
  for (const TypeInfo& t : kTypes) {
    if (name == t.name) return t.type;
  }
  if (name == "NOT_FOUND") return absl::NotFoundError("variable not found by the controller");
  if (name == "IN_USE") return absl::FailedPreconditionError("variable in use by another client");
  return absl::InvalidArgumentError(absl::StrCat("unknown RTDE type name '", name, "'"));
}

size_t RtdeTypeSize(RtdeType type) {
  for (const TypeInfo& t : kTypes) {
    if (t.type == type) return t.size;
  }
  return 0;
}

std::optional<RtdeType> RtdeOutputType(absl::string_view name) {
  for (const Variable& v : kOutputs) {
    if (name == v.name) return v.type;
  }
  if (IsRegister(name, "output_int_register_")) return RtdeType::kInt32;
  if (IsRegister(name, "output_double_register_")) return RtdeType::kDouble;
  // Inputs can be read back as outputs.
  return RtdeInputType(name);
}

std::optional<RtdeType> RtdeInputType(absl::string_view name) {
  for (const Variable& v : kInputs) {
    if (name == v.name) return v.type;
  }
  if (IsRegister(name, "input_int_register_")) return RtdeType::kInt32;
  if (IsRegister(name, "input_double_register_")) return RtdeType::kDouble;
  return std::nullopt;
}

RtdeType TypeOf(const RtdeValue& value) {
  static constexpr RtdeType kByIndex[] = {
      RtdeType::kBool,         RtdeType::kUint8,         RtdeType::kUint32,   RtdeType::kUint64,
      RtdeType::kInt32,        RtdeType::kDouble,        RtdeType::kVector3d, RtdeType::kVector6d,
      RtdeType::kVector6Int32, RtdeType::kVector6Uint32,
  };
  return kByIndex[value.index()];
}

std::string EncodeRtdeFrame(uint8_t type, absl::string_view payload) {
  const size_t max_payload = std::numeric_limits<uint16_t>::max() - kHeaderSize;
  payload = payload.substr(0, max_payload);
  ByteWriter w;
  w.PutU16(static_cast<uint16_t>(payload.size() + kHeaderSize));
  w.PutU8(type);
  w.PutBytes(payload);
  return w.Take();
}

std::string EncodeRtdeFrame(RtdeMessageType type, absl::string_view payload) {
  return EncodeRtdeFrame(static_cast<uint8_t>(type), payload);
}

absl::StatusOr<RtdeFrame> ParseRtdeFrame(absl::string_view frame) {
  ByteReader r(frame);
  const uint16_t size = r.GetU16("RTDE size");
  const uint8_t type = r.GetU8("RTDE type");
  if (!r.ok()) return r.status();
  if (size != frame.size()) {
    return absl::InvalidArgumentError(
        absl::StrCat("RTDE size field ", size, " does not match its ", frame.size(), " bytes"));
  }
  return RtdeFrame{type, std::string(r.Rest())};
}

void RtdeFramer::Append(absl::string_view bytes) { buffer_.append(bytes.data(), bytes.size()); }

absl::StatusOr<std::optional<RtdeFrame>> RtdeFramer::Next() {
  if (buffer_.size() < kHeaderSize) return std::nullopt;
  ByteReader r(buffer_);
  const uint16_t size = *r.U16();
  if (size < kHeaderSize) {
    return absl::DataLossError(absl::StrCat("RTDE stream out of step: size field ", size));
  }
  if (buffer_.size() < size) return std::nullopt;
  RtdeFrame frame{static_cast<uint8_t>(buffer_[2]),
                  buffer_.substr(kHeaderSize, size - kHeaderSize)};
  buffer_.erase(0, size);
  return frame;
}

std::string EncodeRequestProtocolVersion(uint16_t version) {
  ByteWriter w;
  w.PutU16(version);
  return EncodeRtdeFrame(RtdeMessageType::kRequestProtocolVersion, w.data());
}

absl::StatusOr<uint16_t> ParseRequestProtocolVersion(absl::string_view payload) {
  ByteReader r(payload);
  const uint16_t v = r.GetU16("protocol version");
  if (!r.ok()) return r.status();
  if (absl::Status s = ExpectEnd(r, "REQUEST_PROTOCOL_VERSION"); !s.ok()) return s;
  return v;
}

std::string EncodeAccepted(RtdeMessageType type, bool accepted) {
  return EncodeRtdeFrame(type, std::string(1, accepted ? '\1' : '\0'));
}

absl::StatusOr<bool> ParseAccepted(absl::string_view payload) {
  ByteReader r(payload);
  const bool accepted = r.GetBool("accepted");
  if (!r.ok()) return r.status();
  if (absl::Status s = ExpectEnd(r, "accepted reply"); !s.ok()) return s;
  return accepted;
}

std::string EncodeGetUrcontrolVersion() {
  return EncodeRtdeFrame(RtdeMessageType::kGetUrcontrolVersion, "");
}

std::string EncodeUrcontrolVersion(const UrcontrolVersion& version) {
  ByteWriter w;
  w.PutU32(version.major);
  w.PutU32(version.minor);
  w.PutU32(version.bugfix);
  w.PutU32(version.build);
  return EncodeRtdeFrame(RtdeMessageType::kGetUrcontrolVersion, w.data());
}

absl::StatusOr<UrcontrolVersion> ParseUrcontrolVersion(absl::string_view payload) {
  ByteReader r(payload);
  UrcontrolVersion v;
  v.major = r.GetU32("major");
  v.minor = r.GetU32("minor");
  v.bugfix = r.GetU32("bugfix");
  v.build = r.GetU32("build");
  if (!r.ok()) return r.status();
  if (absl::Status s = ExpectEnd(r, "GET_URCONTROL_VERSION"); !s.ok()) return s;
  return v;
}

std::string EncodeSetupOutputs(const SetupOutputsRequest& request) {
  ByteWriter w;
  w.PutDouble(request.frequency);
  w.PutBytes(absl::StrJoin(request.names, ","));
  return EncodeRtdeFrame(RtdeMessageType::kSetupOutputs, w.data());
}

absl::StatusOr<SetupOutputsRequest> ParseSetupOutputs(absl::string_view payload) {
  ByteReader r(payload);
  SetupOutputsRequest request;
  request.frequency = r.GetDouble("frequency");
  if (!r.ok()) return r.status();
  request.names = SplitNames(r.Rest());
  return request;
}

std::string EncodeSetupInputs(const std::vector<std::string>& names) {
  return EncodeRtdeFrame(RtdeMessageType::kSetupInputs, absl::StrJoin(names, ","));
}

std::vector<std::string> ParseSetupInputs(absl::string_view payload) { return SplitNames(payload); }

std::string EncodeSetupReply(RtdeMessageType type, const SetupReply& reply) {
  ByteWriter w;
  w.PutU8(reply.recipe_id);
  w.PutBytes(absl::StrJoin(reply.types, ","));
  return EncodeRtdeFrame(type, w.data());
}

absl::StatusOr<SetupReply> ParseSetupReply(absl::string_view payload) {
  ByteReader r(payload);
  SetupReply reply;
  reply.recipe_id = r.GetU8("recipe id");
  if (!r.ok()) return r.status();
  reply.types = SplitNames(r.Rest());
  return reply;
}

absl::StatusOr<std::vector<RtdeType>> RecipeTypes(const SetupReply& reply,
                                                  const std::vector<std::string>& names) {
  std::vector<RtdeType> types;
  for (size_t i = 0; i < reply.types.size(); ++i) {
    absl::StatusOr<RtdeType> t = ParseRtdeTypeName(reply.types[i]);
    if (!t.ok()) {
      const std::string name = i < names.size() ? names[i] : absl::StrCat("#", i);
      return absl::Status(t.status().code(),
                          absl::StrCat("RTDE variable '", name, "': ", t.status().message()));
    }
    types.push_back(*t);
  }
  if (!names.empty() && names.size() != types.size()) {
    return absl::InvalidArgumentError(absl::StrCat("RTDE setup reply has ", types.size(),
                                                   " types for ", names.size(), " variables"));
  }
  if (reply.recipe_id == 0) return absl::FailedPreconditionError("RTDE recipe refused (id 0)");
  return types;
}

std::string EncodeStart() { return EncodeRtdeFrame(RtdeMessageType::kStart, ""); }
std::string EncodePause() { return EncodeRtdeFrame(RtdeMessageType::kPause, ""); }

std::string EncodeDataPackage(const RtdeDataPackage& package) {
  ByteWriter w;
  w.PutU8(package.recipe_id);
  for (const RtdeValue& value : package.values) {
    std::visit(
        [&w](const auto& v) {
          using T = std::decay_t<decltype(v)>;
          if constexpr (std::is_same_v<T, bool>) {
            w.PutBool(v);
          } else if constexpr (std::is_same_v<T, uint8_t>) {
            w.PutU8(v);
          } else if constexpr (std::is_same_v<T, uint32_t>) {
            w.PutU32(v);
          } else if constexpr (std::is_same_v<T, uint64_t>) {
            w.PutU64(v);
          } else if constexpr (std::is_same_v<T, int32_t>) {
            w.PutI32(v);
          } else if constexpr (std::is_same_v<T, double>) {
            w.PutDouble(v);
          } else if constexpr (std::is_same_v<T, std::array<double, 3>> ||
                               std::is_same_v<T, std::array<double, 6>>) {
            for (double d : v) w.PutDouble(d);
          } else if constexpr (std::is_same_v<T, std::array<int32_t, 6>>) {
            for (int32_t d : v) w.PutI32(d);
          } else {
            for (uint32_t d : v) w.PutU32(d);
          }
        },
        value);
  }
  return EncodeRtdeFrame(RtdeMessageType::kDataPackage, w.data());
}

absl::StatusOr<RtdeDataPackage> ParseDataPackage(absl::string_view payload,
                                                 const std::vector<RtdeType>& types) {
  ByteReader r(payload);
  RtdeDataPackage package;
  package.recipe_id = r.GetU8("recipe id");
  size_t expected = 1;
  for (RtdeType t : types) expected += RtdeTypeSize(t);
  if (payload.size() != expected) {
    return absl::InvalidArgumentError(absl::StrCat("RTDE data package of ", payload.size(),
                                                   " bytes, the recipe needs ", expected));
  }
  for (RtdeType t : types) {
    switch (t) {
      case RtdeType::kBool:
        package.values.emplace_back(r.GetBool());
        break;
      case RtdeType::kUint8:
        package.values.emplace_back(r.GetU8());
        break;
      case RtdeType::kUint32:
        package.values.emplace_back(r.GetU32());
        break;
      case RtdeType::kUint64:
        package.values.emplace_back(r.GetU64());
        break;
      case RtdeType::kInt32:
        package.values.emplace_back(r.GetI32());
        break;
      case RtdeType::kDouble:
        package.values.emplace_back(r.GetDouble());
        break;
      case RtdeType::kVector3d: {
        std::array<double, 3> v{};
        for (double& d : v) d = r.GetDouble();
        package.values.emplace_back(v);
        break;
      }
      case RtdeType::kVector6d: {
        std::array<double, 6> v{};
        for (double& d : v) d = r.GetDouble();
        package.values.emplace_back(v);
        break;
      }
      case RtdeType::kVector6Int32: {
        std::array<int32_t, 6> v{};
        for (int32_t& d : v) d = r.GetI32();
        package.values.emplace_back(v);
        break;
      }
      case RtdeType::kVector6Uint32: {
        std::array<uint32_t, 6> v{};
        for (uint32_t& d : v) d = r.GetU32();
        package.values.emplace_back(v);
        break;
      }
    }
  }
  if (!r.ok()) return r.status();
  return package;
}

std::string EncodeRtdeTextMessage(const RtdeTextMessage& m) {
  ByteWriter w;
  const size_t n = std::min<size_t>(m.message.size(), 255);
  const size_t s = std::min<size_t>(m.source.size(), 255);
  w.PutU8(static_cast<uint8_t>(n));
  w.PutBytes(absl::string_view(m.message).substr(0, n));
  w.PutU8(static_cast<uint8_t>(s));
  w.PutBytes(absl::string_view(m.source).substr(0, s));
  w.PutU8(m.level);
  return EncodeRtdeFrame(RtdeMessageType::kTextMessage, w.data());
}

absl::StatusOr<RtdeTextMessage> ParseRtdeTextMessage(absl::string_view payload) {
  ByteReader r(payload);
  RtdeTextMessage m;
  m.message = r.GetBytes(r.GetU8("message length"), "message");
  m.source = r.GetBytes(r.GetU8("source length"), "source");
  m.level = r.GetU8("warning level");
  if (!r.ok()) return r.status();
  return m;
}

}  // namespace cornerpose::ur
