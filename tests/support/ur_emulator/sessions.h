// The emulator's three interfaces as byte-level sessions, without sockets:
// what a dashboard command answers, how primary script text is split into
// programs and control words, and an RTDE session's handshake and data
// packages. servers.cc puts them on TCP.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "absl/strings/string_view.h"
#include "robot_client/ur/rtde.h"
#include "tests/support/ur_emulator/controller.h"

namespace cornerpose::ur_emulator {

// ---- Dashboard (29999) ----

// The banner is ur::kDashboardBanner (robot_client/ur/dashboard.h). The one-line reply (no newline)
// to one command line; `*close` is set for `quit`, after which the server closes the connection.
std::string DashboardReply(Controller& controller, absl::string_view command, bool* close);

// ---- Primary (30001) ----

// Splits the text a client sends into whole scripts and control words: a
// `def`/`sec` program runs from its header line through `end` in column 1;
// outside a program, a control word (`power on`, `power off`, `set robotmode
// run`, `set unlock protective stop`, `stop program`) is one line, and any
// other non-blank line is a one-line script.
class PrimaryScriptAssembler {
 public:
  struct Item {
    bool control_word = false;
    std::string text;  // the control word, or the script with its newlines
  };
  // One line without its '\n'.
  std::optional<Item> AddLine(absl::string_view line);

 private:
  bool in_program_ = false;
  std::string buffer_;
};

// Applies a control word to the controller.
void ApplyPrimaryControlWord(Controller& controller, absl::string_view word);

// The VERSION message a primary client gets first.
std::string EncodePrimaryVersion(const UrEmulatorOptions& options);
// ROBOT_STATE: robot mode, joint, Cartesian and masterboard data.
// Digital outputs: standard bits 0-7, configurable 8-15, tool 16-17.
std::string EncodePrimaryState(const RobotSnapshot& snapshot);
// KEY / TEXT / RUNTIME_EXCEPTION / SAFETY_MODE for one event.
std::string EncodePrimaryEvent(const ControllerEvent& event);

// ---- RTDE (30004) ----

class RtdeSession {
 public:
  explicit RtdeSession(const UrEmulatorOptions& options) : options_(options) {}

  // Handles one client message; returns the bytes to answer (maybe none).
  std::string Handle(const ur::RtdeFrame& frame);

  // Data packages flow after START, until PAUSE.
  bool streaming() const { return streaming_; }
  // Wall seconds between data packages.
  double period_s() const { return 1.0 / frequency_hz_; }
  // The output recipe's data package for `snapshot`.
  std::string DataPackage(const RobotSnapshot& snapshot) const;

 private:
  const UrEmulatorOptions& options_;
  uint16_t protocol_version_ = 1;
  uint8_t next_recipe_id_ = 1;
  uint8_t output_recipe_id_ = 0;  // 0: none
  std::vector<std::string> output_names_;
  std::vector<ur::RtdeType> output_types_;
  double frequency_hz_ = 125.0;
  bool streaming_ = false;
};

// The value of an RTDE output variable for `snapshot`; variables the
// emulator does not model (registers, currents, ...) are zero.
ur::RtdeValue RtdeOutputValue(absl::string_view name, ur::RtdeType type,
                              const RobotSnapshot& snapshot);

}  // namespace cornerpose::ur_emulator
