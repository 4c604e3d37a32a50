// Dashboard server (port 29999) replies, and the robot / safety mode
// enumerations shared by all interfaces (URCL ur/datatypes.h; see
// shared/design/ur-interface.md sections 2.4, 2.5). Parsing is lenient:
// surrounding blanks, letter case and the CB2-era variants are accepted.
#pragma once

#include <optional>
#include <string>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"

namespace cornerpose::ur {

enum class RobotMode : int {
  kNoController = -1,
  kDisconnected = 0,
  kConfirmSafety = 1,
  kBooting = 2,
  kPowerOff = 3,
  kPowerOn = 4,
  kIdle = 5,
  kBackdrive = 6,
  kRunning = 7,
  kUpdatingFirmware = 8,
};
// "RUNNING" etc.; "UNKNOWN" outside the enumeration.
const char* RobotModeName(RobotMode mode);
std::optional<RobotMode> RobotModeFromName(absl::string_view name);
std::optional<RobotMode> RobotModeFromInt(int value);

enum class SafetyMode : int {
  kNormal = 1,
  kReduced = 2,
  kProtectiveStop = 3,
  kRecovery = 4,
  kSafeguardStop = 5,
  kSystemEmergencyStop = 6,
  kRobotEmergencyStop = 7,
  kViolation = 8,
  kFault = 9,
  kValidateJointId = 10,
  kUndefinedSafetyMode = 11,
  kAutomaticModeSafeguardStop = 12,
  kSystemThreePositionEnablingStop = 13,
};
// "PROTECTIVE_STOP" etc.; "UNKNOWN" outside 1..13.
const char* SafetyModeName(SafetyMode mode);
std::optional<SafetyMode> SafetyModeFromName(absl::string_view name);
std::optional<SafetyMode> SafetyModeFromInt(int value);

// The banner the server sends on connect.
inline constexpr char kDashboardBanner[] = "Connected: Universal Robots Dashboard Server";

// "Robotmode: RUNNING" -> kRunning. INVALID_ARGUMENT for anything else.
absl::StatusOr<RobotMode> ParseRobotModeReply(absl::string_view line);
// "Safetystatus: PROTECTIVE_STOP" or "Safetymode: NORMAL".
absl::StatusOr<SafetyMode> ParseSafetyReply(absl::string_view line);
// "Program running: true" (also "Robot running: True").
absl::StatusOr<bool> ParseRunningReply(absl::string_view line);

enum class ProgramState { kStopped, kPlaying, kPaused };
const char* ProgramStateName(ProgramState state);
struct ProgramStateReply {
  ProgramState state = ProgramState::kStopped;
  std::string program;  // may be empty
};
// "STOPPED wait_program.urp", "PLAYING <unnamed>".
absl::StatusOr<ProgramStateReply> ParseProgramStateReply(absl::string_view line);

}  // namespace cornerpose::ur
