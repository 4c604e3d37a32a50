// ur_emulator: the UR controller emulator as a process, for demos and the
// container cell. Serves the dashboard, primary and RTDE ports until SIGINT
// or SIGTERM and prints one line per program it ran.
#include <csignal>
#include <cstdio>
#include <string>
#include <vector>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/flags/usage.h"
#include "absl/strings/str_format.h"
#include "robot_client/ur/kinematics.h"
#include "tests/support/ur_emulator/ur_emulator.h"

ABSL_FLAG(std::string, host, "127.0.0.1", "Address to listen on (0.0.0.0 for every interface).");
ABSL_FLAG(int, dashboard_port, 29999, "Dashboard server port.");
ABSL_FLAG(int, primary_port, 30001, "Primary client interface port (URScript in).");
ABSL_FLAG(int, rtde_port, 30004, "RTDE port.");
ABSL_FLAG(std::string, model, "ur5e", "Arm model: ur5 or ur5e.");
ABSL_FLAG(double, time_scale, 1.0, "Simulated seconds per wall-clock second (> 0).");
ABSL_FLAG(bool, powered, false,
          "Start powered on with brakes released (RUNNING) instead of POWER_OFF.");

namespace {

volatile std::sig_atomic_t g_stop = 0;
void OnSignal(int) { g_stop = 1; }

}  // namespace

int main(int argc, char** argv) {
  using namespace cornerpose;
  absl::SetProgramUsageMessage(
      "UR controller emulator: dashboard, primary (URScript) and RTDE servers over a "
      "simulated UR5/UR5e.");
  absl::ParseCommandLine(argc, argv);

  ur_emulator::UrEmulatorOptions options;
  options.host = absl::GetFlag(FLAGS_host);
  options.dashboard_port = absl::GetFlag(FLAGS_dashboard_port);
  options.primary_port = absl::GetFlag(FLAGS_primary_port);
  options.rtde_port = absl::GetFlag(FLAGS_rtde_port);
  options.time_scale = absl::GetFlag(FLAGS_time_scale);
  options.start_powered_off = !absl::GetFlag(FLAGS_powered);
  auto model = ur::ParseArmModel(absl::GetFlag(FLAGS_model));
  if (!model.ok()) {
    std::fprintf(stderr, "ur_emulator: %s\n", std::string(model.status().message()).c_str());
    return 2;
  }
  options.model = *model;

  auto emulator = ur_emulator::UrEmulator::Start(options);
  if (!emulator.ok()) {
    std::fprintf(stderr, "ur_emulator: %s\n", emulator.status().ToString().c_str());
    return 1;
  }
  std::signal(SIGINT, OnSignal);
  std::signal(SIGTERM, OnSignal);
  std::printf("ur_emulator: %s on %s, dashboard %d, primary %d, rtde %d, time scale %g, %s\n",
              ur::ArmModelName(options.model), options.host.c_str(), (*emulator)->dashboard_port(),
              (*emulator)->primary_port(), (*emulator)->rtde_port(), options.time_scale,
              options.start_powered_off ? "powered off" : "running");
  std::fflush(stdout);

  // Programs usually end in order; a compile error arriving while another
  // program runs ends first. Print each one once, when it ends.
  std::vector<bool> printed;
  size_t finished = 0;
  while (!g_stop) {
    (*emulator)->WaitFor(
        [&](const ur_emulator::RobotSnapshot& s) { return s.programs_finished > finished; },
        absl::Milliseconds(200));
    const auto programs = (*emulator)->Programs();
    printed.resize(programs.size(), false);
    finished = 0;
    for (size_t i = 0; i < programs.size(); ++i) {
      const auto& p = programs[i];
      if (p.outcome == ur_emulator::ProgramOutcome::kRunning) continue;
      ++finished;
      if (printed[i]) continue;
      printed[i] = true;
      std::printf("program %s: %s%s%s, %.3f s simulated, %zu steps\n", p.name.c_str(),
                  ur_emulator::ProgramOutcomeName(p.outcome), p.error_text.empty() ? "" : " ",
                  p.error_text.c_str(), p.end_time_s - p.start_time_s, p.steps.size());
      std::fflush(stdout);
    }
  }
  std::printf("ur_emulator: stopping\n");
  return 0;
}
