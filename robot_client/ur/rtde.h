// RTDE (port 30004), protocol version 2: message framing (uint16 size incl.
// the 3-byte header, uint8 type), the handshake messages, the variable type
// table and data packages. Layouts: URCL and UR's RTDE_Python_Client_Library
// (shared/design/ur-interface.md section 2.3); both sides are here so the
// controller emulator speaks the same bytes.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"

namespace cornerpose::ur {

// Message types: ASCII letters.
enum class RtdeMessageType : uint8_t {
  kRequestProtocolVersion = 'V',
  kGetUrcontrolVersion = 'v',
  kTextMessage = 'M',
  kDataPackage = 'U',
  kSetupOutputs = 'O',
  kSetupInputs = 'I',
  kStart = 'S',
  kPause = 'P',
};

constexpr uint16_t kRtdeProtocolVersion = 2;

enum class RtdeType {
  kBool,
  kUint8,
  kUint32,
  kUint64,
  kInt32,
  kDouble,
  kVector3d,
  kVector6d,
  kVector6Int32,
  kVector6Uint32,
};

// "BOOL", "UINT8", ..., "VECTOR6UINT32" (the controller's type names).
const char* RtdeTypeName(RtdeType type);
// INVALID_ARGUMENT for anything else, NOT_FOUND for the controller's
// "NOT_FOUND" and FAILED_PRECONDITION for "IN_USE".
absl::StatusOr<RtdeType> ParseRtdeTypeName(absl::string_view name);
// Bytes on the wire.
size_t RtdeTypeSize(RtdeType type);

// The controller's type for an output (controller -> client) / input
// variable name; nullopt for names this table does not know.
// Outputs include timestamp, target_q, actual_q, actual_qd, actual_TCP_pose,
// target_TCP_pose, actual_TCP_speed, tcp_offset, actual_digital_input_bits,
// actual_digital_output_bits, robot_mode, joint_mode, safety_mode,
// safety_status, safety_status_bits, robot_status_bits, runtime_state,
// speed_scaling, target_speed_fraction, output_{int,double}_register_N.
std::optional<RtdeType> RtdeOutputType(absl::string_view name);
// speed_slider_mask, speed_slider_fraction, standard/configurable/tool
// digital output (mask), input_{int,double}_register_N.
std::optional<RtdeType> RtdeInputType(absl::string_view name);

using RtdeValue =
    std::variant<bool, uint8_t, uint32_t, uint64_t, int32_t, double, std::array<double, 3>,
                 std::array<double, 6>, std::array<int32_t, 6>, std::array<uint32_t, 6>>;
RtdeType TypeOf(const RtdeValue& value);

// One message: type and payload (after the header).
struct RtdeFrame {
  uint8_t type = 0;
  std::string payload;
};

// Header + payload. A payload too long for the uint16 size is cut (callers
// keep recipes short; the largest real message is far below 64 KiB).
std::string EncodeRtdeFrame(uint8_t type, absl::string_view payload);
std::string EncodeRtdeFrame(RtdeMessageType type, absl::string_view payload);
// One complete message; the size field must equal frame.size().
absl::StatusOr<RtdeFrame> ParseRtdeFrame(absl::string_view frame);

// Splits a TCP byte stream into messages.
class RtdeFramer {
 public:
  void Append(absl::string_view bytes);
  // nullopt when more bytes are needed; DATA_LOSS for a size field < 3.
  absl::StatusOr<std::optional<RtdeFrame>> Next();

 private:
  std::string buffer_;
};

// ---- Handshake (complete frames; Parse* take the payload) ----

// Client: `00 05 56 00 02`.
std::string EncodeRequestProtocolVersion(uint16_t version = kRtdeProtocolVersion);
absl::StatusOr<uint16_t> ParseRequestProtocolVersion(absl::string_view payload);

// Controller's one-byte answer to V, S, P: `00 04 <type> 01`.
std::string EncodeAccepted(RtdeMessageType type, bool accepted);
absl::StatusOr<bool> ParseAccepted(absl::string_view payload);

struct UrcontrolVersion {
  uint32_t major = 0, minor = 0, bugfix = 0, build = 0;
};
std::string EncodeGetUrcontrolVersion();
std::string EncodeUrcontrolVersion(const UrcontrolVersion& version);
absl::StatusOr<UrcontrolVersion> ParseUrcontrolVersion(absl::string_view payload);

// v2 setup outputs: double frequency [Hz], comma-separated names.
struct SetupOutputsRequest {
  double frequency = 0.0;
  std::vector<std::string> names;
};
std::string EncodeSetupOutputs(const SetupOutputsRequest& request);
absl::StatusOr<SetupOutputsRequest> ParseSetupOutputs(absl::string_view payload);

std::string EncodeSetupInputs(const std::vector<std::string>& names);
std::vector<std::string> ParseSetupInputs(absl::string_view payload);

// Controller's answer to O and I: recipe id (0 = failed) and one type name
// per requested variable ("NOT_FOUND" / "IN_USE" for refused ones).
struct SetupReply {
  uint8_t recipe_id = 0;
  std::vector<std::string> types;
};
std::string EncodeSetupReply(RtdeMessageType type, const SetupReply& reply);
absl::StatusOr<SetupReply> ParseSetupReply(absl::string_view payload);
// The recipe's types, or the error naming the first refused variable
// (`names` gives the names for the message; may be empty).
absl::StatusOr<std::vector<RtdeType>> RecipeTypes(const SetupReply& reply,
                                                  const std::vector<std::string>& names);

std::string EncodeStart();
std::string EncodePause();

// ---- Data packages ----

struct RtdeDataPackage {
  uint8_t recipe_id = 0;
  std::vector<RtdeValue> values;
};
// The complete frame; the values are packed in order, no padding.
std::string EncodeDataPackage(const RtdeDataPackage& package);
// Payload (after the header): recipe id, then one value per type. The
// payload size must match the recipe exactly.
absl::StatusOr<RtdeDataPackage> ParseDataPackage(absl::string_view payload,
                                                 const std::vector<RtdeType>& types);

// ---- Text message (v2) ----

enum class RtdeTextLevel : uint8_t { kException = 0, kError = 1, kWarning = 2, kInfo = 3 };
struct RtdeTextMessage {
  std::string message;
  std::string source;
  uint8_t level = static_cast<uint8_t>(RtdeTextLevel::kInfo);
};
std::string EncodeRtdeTextMessage(const RtdeTextMessage& m);
absl::StatusOr<RtdeTextMessage> ParseRtdeTextMessage(absl::string_view payload);

}  // namespace cornerpose::ur
