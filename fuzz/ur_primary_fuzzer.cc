// The UR primary / secondary interface (robot_client/ur/primary.h): the input
// is a TCP byte stream split by PrimaryFramer, and every package it yields
// (or the whole input, when it is one) goes through ParsePrimaryPackage. A
// package that parses must re-encode to bytes that parse back to the same
// package. (Not to the very same bytes: a bool byte other than 0 or 1 reads
// as true and is written back as 1.)
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <string>

#include "fuzz/fuzz_input.h"
#include "robot_client/ur/primary.h"

namespace {

void ParseOne(absl::string_view frame) {
  const absl::StatusOr<cornerpose::ur::PrimaryPackage> package =
      cornerpose::ur::ParsePrimaryPackage(frame);
  if (!package.ok()) return;
  const std::string encoded = cornerpose::ur::EncodePrimaryPackage(*package);
  const absl::StatusOr<cornerpose::ur::PrimaryPackage> again =
      cornerpose::ur::ParsePrimaryPackage(encoded);
  cornerpose::fuzz::Require(encoded.size() == frame.size(), "re-encoding keeps the size");
  cornerpose::fuzz::Require(again.ok() && again->index() == package->index() &&
                                cornerpose::ur::EncodePrimaryPackage(*again) == encoded,
                            "a re-encoded primary package parses back to the same package");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const absl::string_view input = cornerpose::fuzz::AsText(data, size);
  ParseOne(input);
  // The same bytes as a stream arriving in reads of up to 7 bytes: the
  // framer must find the same packages whatever the read boundaries.
  cornerpose::ur::PrimaryFramer framer;
  size_t pos = 0;
  while (true) {
    if (pos < input.size()) {
      const size_t n = std::min<size_t>(1 + pos % 7, input.size() - pos);
      framer.Append(input.substr(pos, n));
      pos += n;
    }
    const absl::StatusOr<std::optional<std::string>> next = framer.Next();
    if (!next.ok()) break;  // stream out of step: the client closes it
    if (next->has_value()) {
      ParseOne(**next);
    } else if (pos >= input.size()) {
      break;
    }
  }
  return 0;
}
