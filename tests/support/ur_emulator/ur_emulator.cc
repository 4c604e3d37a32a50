#include "tests/support/ur_emulator/ur_emulator.h"

#include "tests/support/ur_emulator/servers.h"

namespace cornerpose::ur_emulator {

absl::StatusOr<std::unique_ptr<UrEmulator>> UrEmulator::Start(UrEmulatorOptions options) {
  if (!(options.time_scale > 0.0)) {
    return absl::InvalidArgumentError("time_scale must be > 0");
  }
  if (!(options.control_period_s > 0.0) || !(options.primary_state_hz > 0.0) ||
      !(options.rtde_max_frequency_hz > 0.0)) {
    return absl::InvalidArgumentError(
        "control_period_s, primary_state_hz and rtde_max_frequency_hz must be > 0");
  }
  for (int port : {options.dashboard_port, options.primary_port, options.rtde_port}) {
    if (port < 0 || port > 65535) {
      return absl::InvalidArgumentError("ports must be in [0, 65535]");
    }
  }
  std::unique_ptr<UrEmulator> emulator(new UrEmulator());
  emulator->controller_ = std::make_unique<Controller>(std::move(options));
  emulator->servers_ = std::make_unique<Servers>(*emulator->controller_);
  if (absl::Status status = emulator->servers_->Start(); !status.ok()) return status;
  return emulator;
}

UrEmulator::~UrEmulator() {
  servers_.reset();  // joins every client thread before the controller goes
  controller_.reset();
}

int UrEmulator::dashboard_port() const { return servers_->dashboard_port(); }
int UrEmulator::primary_port() const { return servers_->primary_port(); }
int UrEmulator::rtde_port() const { return servers_->rtde_port(); }

void UrEmulator::DropConnections() { servers_->DropConnections(); }
void UrEmulator::SetLinksSilent(bool silent) { servers_->SetSilent(silent); }
void UrEmulator::SetRtdeStalled(bool stalled) { servers_->SetRtdeStalled(stalled); }

bool UrEmulator::WaitForProgramsFinished(size_t count, absl::Duration timeout) const {
  return WaitFor([count](const RobotSnapshot& s) { return s.programs_finished >= count; }, timeout);
}

}  // namespace cornerpose::ur_emulator
