// RTDE (robot_client/ur/rtde.h). Input: one byte n (mod 17), n bytes naming
// a recipe's variable types (mod 10), then an RTDE byte stream. Each frame
// the framer yields goes through the parser for its type, data packages
// through the recipe (the one from the input's head, or from the last setup
// reply that parsed), as a client decoding a controller's replies would.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "fuzz/fuzz_input.h"
#include "robot_client/ur/rtde.h"

namespace ur = cornerpose::ur;
using cornerpose::fuzz::Require;

namespace {

void ParsePayload(const ur::RtdeFrame& frame, std::vector<ur::RtdeType>* recipe) {
  const absl::string_view payload = frame.payload;
  switch (static_cast<ur::RtdeMessageType>(frame.type)) {
    case ur::RtdeMessageType::kRequestProtocolVersion:
      (void)ur::ParseRequestProtocolVersion(payload);
      (void)ur::ParseAccepted(payload);
      break;
    case ur::RtdeMessageType::kGetUrcontrolVersion:
      (void)ur::ParseUrcontrolVersion(payload);
      break;
    case ur::RtdeMessageType::kTextMessage:
      (void)ur::ParseRtdeTextMessage(payload);
      break;
    case ur::RtdeMessageType::kSetupOutputs:
    case ur::RtdeMessageType::kSetupInputs: {
      (void)ur::ParseSetupOutputs(payload);
      for (const std::string& name : ur::ParseSetupInputs(payload)) {
        (void)ur::RtdeOutputType(name);
        (void)ur::RtdeInputType(name);
      }
      const absl::StatusOr<ur::SetupReply> reply = ur::ParseSetupReply(payload);
      if (!reply.ok()) break;
      absl::StatusOr<std::vector<ur::RtdeType>> types = ur::RecipeTypes(*reply, {});
      if (types.ok()) *recipe = *std::move(types);
      break;
    }
    case ur::RtdeMessageType::kDataPackage: {
      const absl::StatusOr<ur::RtdeDataPackage> package = ur::ParseDataPackage(payload, *recipe);
      if (!package.ok()) break;
      Require(package->values.size() == recipe->size(), "one value per recipe variable");
      for (size_t i = 0; i < recipe->size(); ++i) {
        Require(ur::TypeOf(package->values[i]) == (*recipe)[i], "values have the recipe's types");
      }
      // Re-encoded, it parses back to the same package (bytes may differ
      // only where a bool byte other than 0 or 1 became 1).
      const std::string encoded = ur::EncodeDataPackage(*package);
      Require(encoded.size() == payload.size() + 3, "re-encoding keeps the size");
      const absl::StatusOr<ur::RtdeDataPackage> again =
          ur::ParseDataPackage(absl::string_view(encoded).substr(3), *recipe);
      Require(again.ok() && ur::EncodeDataPackage(*again) == encoded,
              "a re-encoded data package parses back to the same package");
      break;
    }
    default:
      (void)ur::ParseAccepted(payload);
      break;
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  absl::string_view input = cornerpose::fuzz::AsText(data, size);
  std::vector<ur::RtdeType> recipe;
  if (!input.empty()) {
    const size_t n = std::min<size_t>(static_cast<uint8_t>(input[0]) % 17, input.size() - 1);
    for (size_t i = 0; i < n; ++i) {
      recipe.push_back(static_cast<ur::RtdeType>(static_cast<uint8_t>(input[1 + i]) % 10));
    }
    input.remove_prefix(1 + n);
  }
  if (const absl::StatusOr<ur::RtdeFrame> whole = ur::ParseRtdeFrame(input); whole.ok()) {
    Require(ur::EncodeRtdeFrame(whole->type, whole->payload) == input,
            "a parsed RTDE frame re-encodes to its bytes");
  }
  ur::RtdeFramer framer;
  framer.Append(input);
  while (true) {
    const absl::StatusOr<std::optional<ur::RtdeFrame>> next = framer.Next();
    if (!next.ok() || !next->has_value()) break;
    ParsePayload(**next, &recipe);
  }
  return 0;
}
