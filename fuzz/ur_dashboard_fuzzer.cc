// Dashboard server replies (robot_client/ur/dashboard.h): every line of the
// input through every reply parser and the mode-name lookups.
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "absl/strings/str_split.h"
#include "fuzz/fuzz_input.h"
#include "robot_client/ur/dashboard.h"

namespace ur = cornerpose::ur;
using cornerpose::fuzz::Require;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  for (absl::string_view line : absl::StrSplit(cornerpose::fuzz::AsText(data, size), '\n')) {
    if (const absl::StatusOr<ur::RobotMode> mode = ur::ParseRobotModeReply(line); mode.ok()) {
      Require(std::strcmp(ur::RobotModeName(*mode), "UNKNOWN") != 0, "a parsed robot mode is known");
    }
    if (const absl::StatusOr<ur::SafetyMode> mode = ur::ParseSafetyReply(line); mode.ok()) {
      Require(std::strcmp(ur::SafetyModeName(*mode), "UNKNOWN") != 0,
              "a parsed safety mode is known");
    }
    (void)ur::ParseRunningReply(line);
    if (const absl::StatusOr<ur::ProgramStateReply> state = ur::ParseProgramStateReply(line);
        state.ok()) {
      (void)ur::ProgramStateName(state->state);
    }
    (void)ur::RobotModeFromName(line);
    (void)ur::SafetyModeFromName(line);
  }
  return 0;
}
