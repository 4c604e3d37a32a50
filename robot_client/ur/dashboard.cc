#include "robot_client/ur/dashboard.h"

#include "absl/status/status.h"
#include "absl/strings/ascii.h"
#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/strip.h"

namespace cornerpose::ur {
namespace {

struct RobotModeEntry {
  RobotMode mode;
  const char* name;
};
constexpr RobotModeEntry kRobotModes[] = {
    {RobotMode::kNoController, "NO_CONTROLLER"},
    {RobotMode::kDisconnected, "DISCONNECTED"},
    {RobotMode::kConfirmSafety, "CONFIRM_SAFETY"},
    {RobotMode::kBooting, "BOOTING"},
    {RobotMode::kPowerOff, "POWER_OFF"},
    {RobotMode::kPowerOn, "POWER_ON"},
    {RobotMode::kIdle, "IDLE"},
    {RobotMode::kBackdrive, "BACKDRIVE"},
    {RobotMode::kRunning, "RUNNING"},
    {RobotMode::kUpdatingFirmware, "UPDATING_FIRMWARE"},
};

struct SafetyModeEntry {
  SafetyMode mode;
  const char* name;
};
constexpr SafetyModeEntry kSafetyModes[] = {
    {SafetyMode::kNormal, "NORMAL"},
    {SafetyMode::kReduced, "REDUCED"},
    {SafetyMode::kProtectiveStop, "PROTECTIVE_STOP"},
    {SafetyMode::kRecovery, "RECOVERY"},
    {SafetyMode::kSafeguardStop, "SAFEGUARD_STOP"},
    {SafetyMode::kSystemEmergencyStop, "SYSTEM_EMERGENCY_STOP"},
    {SafetyMode::kRobotEmergencyStop, "ROBOT_EMERGENCY_STOP"},
    {SafetyMode::kViolation, "VIOLATION"},
    {SafetyMode::kFault, "FAULT"},
    {SafetyMode::kValidateJointId, "VALIDATE_JOINT_ID"},
    {SafetyMode::kUndefinedSafetyMode, "UNDEFINED_SAFETY_MODE"},
    {SafetyMode::kAutomaticModeSafeguardStop, "AUTOMATIC_MODE_SAFEGUARD_STOP"},
    {SafetyMode::kSystemThreePositionEnablingStop, "SYSTEM_THREE_POSITION_ENABLING_STOP"},
};

// The value after "<key>:" (case-insensitive key), trimmed; nullopt when the
// line does not start with the key.
std::optional<absl::string_view> ValueAfter(absl::string_view line, absl::string_view key) {
  line = absl::StripAsciiWhitespace(line);
  if (!absl::StartsWithIgnoreCase(line, key)) return std::nullopt;
  line.remove_prefix(key.size());
  line = absl::StripLeadingAsciiWhitespace(line);
  if (!absl::ConsumePrefix(&line, ":")) return std::nullopt;
  return absl::StripAsciiWhitespace(line);
}

absl::Status Unexpected(absl::string_view what, absl::string_view line) {
  return absl::InvalidArgumentError(
      absl::StrCat("unexpected dashboard reply to ", what, ": '", line, "'"));
}

}  // namespace

const char* RobotModeName(RobotMode mode) {
  for (const RobotModeEntry& e : kRobotModes) {
    if (e.mode == mode) return e.name;
  }
  return "UNKNOWN";
}

std::optional<RobotMode> RobotModeFromName(absl::string_view name) {
  name = absl::StripAsciiWhitespace(name);
  for (const RobotModeEntry& e : kRobotModes) {
    if (absl::EqualsIgnoreCase(name, e.name)) return e.mode;
  }
  return std::nullopt;
}

std::optional<RobotMode> RobotModeFromInt(int value) {
  if (value < -1 || value > 8) return std::nullopt;
  return static_cast<RobotMode>(value);
}

const char* SafetyModeName(SafetyMode mode) {
  for (const SafetyModeEntry& e : kSafetyModes) {
    if (e.mode == mode) return e.name;
  }
  return "UNKNOWN";
}

std::optional<SafetyMode> SafetyModeFromName(absl::string_view name) {
  name = absl::StripAsciiWhitespace(name);
  for (const SafetyModeEntry& e : kSafetyModes) {
    if (absl::EqualsIgnoreCase(name, e.name)) return e.mode;
  }
  return std::nullopt;
}

std::optional<SafetyMode> SafetyModeFromInt(int value) {
  if (value < 1 || value > 13) return std::nullopt;
  return static_cast<SafetyMode>(value);
}

absl::StatusOr<RobotMode> ParseRobotModeReply(absl::string_view line) {
  const std::optional<absl::string_view> value = ValueAfter(line, "Robotmode");
  if (!value) return Unexpected("robotmode", line);
  if (std::optional<RobotMode> mode = RobotModeFromName(*value)) return *mode;
  return Unexpected("robotmode", line);
}

absl::StatusOr<SafetyMode> ParseSafetyReply(absl::string_view line) {
  std::optional<absl::string_view> value = ValueAfter(line, "Safetystatus");
  if (!value) value = ValueAfter(line, "Safetymode");
  if (!value) return Unexpected("safetystatus/safetymode", line);
  if (std::optional<SafetyMode> mode = SafetyModeFromName(*value)) return *mode;
  return Unexpected("safetystatus/safetymode", line);
}

absl::StatusOr<bool> ParseRunningReply(absl::string_view line) {
  std::optional<absl::string_view> value = ValueAfter(line, "Program running");
  if (!value) value = ValueAfter(line, "Robot running");
  if (!value) return Unexpected("running", line);
  if (absl::EqualsIgnoreCase(*value, "true")) return true;
  if (absl::EqualsIgnoreCase(*value, "false")) return false;
  return Unexpected("running", line);
}

const char* ProgramStateName(ProgramState state) {
  switch (state) {
    case ProgramState::kStopped:
      return "STOPPED";
    case ProgramState::kPlaying:
      return "PLAYING";
    case ProgramState::kPaused:
      return "PAUSED";
  }
  return "UNKNOWN";
}

absl::StatusOr<ProgramStateReply> ParseProgramStateReply(absl::string_view line) {
  const absl::string_view trimmed = absl::StripAsciiWhitespace(line);
  const size_t space = trimmed.find(' ');
  const absl::string_view word = trimmed.substr(0, space);
  ProgramStateReply reply;
  if (absl::EqualsIgnoreCase(word, "STOPPED")) {
    reply.state = ProgramState::kStopped;
  } else if (absl::EqualsIgnoreCase(word, "PLAYING")) {
    reply.state = ProgramState::kPlaying;
  } else if (absl::EqualsIgnoreCase(word, "PAUSED")) {
    reply.state = ProgramState::kPaused;
  } else {
    return Unexpected("programState", line);
  }
  if (space != absl::string_view::npos) {
    reply.program = std::string(absl::StripAsciiWhitespace(trimmed.substr(space + 1)));
  }
  return reply;
}

}  // namespace cornerpose::ur
