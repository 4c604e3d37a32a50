// The simulated UR controller behind the emulator's servers: robot and
// safety modes, joint state over simulated time, URScript execution in a
// controller thread, fault injection, and a record of every program. No
// networking; the dashboard / primary / RTDE servers drive it.
#pragma once

#include <Eigen/Geometry>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "absl/time/time.h"
#include "robot_client/ur/kinematics.h"
#include "robot_client/ur/pose.h"
#include "tests/support/ur_emulator/options.h"
#include "tests/support/ur_emulator/urscript.h"

namespace cornerpose::ur_emulator {

// Wire codes (ur-interface.md section 2.5).
inline constexpr int kRobotModePowerOff = 3;
inline constexpr int kRobotModePowerOn = 4;
inline constexpr int kRobotModeIdle = 5;
inline constexpr int kRobotModeRunning = 7;
inline constexpr int kSafetyModeNormal = 1;
inline constexpr int kSafetyModeProtectiveStop = 3;
inline constexpr int kSafetyModeRobotEmergencyStop = 7;

// One executed statement.
struct ExecutedStep {
  std::string kind;  // the function: "movej", "movel", "set_tool_digital_out", "sleep", ...
  int line = 0;      // in the program text
  std::string args;  // the arguments as written back, for messages
  // Moves: the commanded TCP pose in the base frame (a joint target
  // converted through FK and the TCP offset in force).
  std::optional<ur::UrPose> target;
  // State at the end of the step (where it was cut off if !completed).
  ur::Joints joints{};
  ur::UrPose tcp;
  uint32_t tool_outputs = 0;      // bit n = tool output n
  uint32_t standard_outputs = 0;  // bit n = standard output n
  uint32_t configurable_outputs = 0;
  double start_time_s = 0.0;  // simulated
  double end_time_s = 0.0;    // simulated
  bool completed = true;      // false: cut off by a stop, an abort or an error
};

enum class ProgramOutcome {
  kRunning,           // still executing
  kCompleted,         // reached `end`
  kAborted,           // replaced by a new program, `stop program`, dashboard stop, power off
  kProtectiveStop,    // protective stop (injected or protective_stop())
  kRuntimeException,  // did not compile, or failed while running (error_text)
  kRejected,          // robot not RUNNING / not in NORMAL safety mode: not started
};
const char* ProgramOutcomeName(ProgramOutcome outcome);

struct ExecutedProgram {
  std::string name;
  std::string text;  // as received
  ProgramOutcome outcome = ProgramOutcome::kRunning;
  std::string error_text;  // kRuntimeException / kRejected
  int error_line = 0;
  int error_column = 0;
  std::vector<ExecutedStep> steps;
  double start_time_s = 0.0;  // simulated
  double end_time_s = 0.0;
};

// A consistent copy of the controller state.
struct RobotSnapshot {
  double time_s = 0.0;  // simulated seconds since start
  ur::Joints joints{};
  ur::Joints target_joints{};
  ur::Joints joint_speeds{};
  ur::UrPose tcp;         // FK(joints) * tcp_offset
  ur::UrPose target_tcp;  // FK(target_joints) * tcp_offset
  ur::UrPose tcp_offset;
  uint32_t tool_outputs = 0;
  uint32_t standard_outputs = 0;
  uint32_t configurable_outputs = 0;
  int robot_mode = kRobotModePowerOff;
  int safety_mode = kSafetyModeNormal;
  bool program_running = false;
  std::string program_name;  // running or last
  // Programs recorded so far, including the running one.
  size_t programs_recorded = 0;
  // Programs that have ended (any outcome).
  size_t programs_finished = 0;
};

// What the primary interface reports, in order.
struct ControllerEvent {
  enum class Kind { kProgramStarted, kProgramStopped, kText, kRuntimeException, kSafetyMode };
  Kind kind = Kind::kText;
  std::string text;  // program name / message / exception text
  int line = 0;      // kRuntimeException
  int column = 0;
  int safety_mode = 0;  // kSafetyMode
  double time_s = 0.0;
};

class Controller {
 public:
  // Starts the controller thread.
  explicit Controller(UrEmulatorOptions options);
  // Stops any program and joins the thread.
  ~Controller();
  Controller(const Controller&) = delete;
  Controller& operator=(const Controller&) = delete;

  const UrEmulatorOptions& options() const { return options_; }

  // Script text from the primary port: a whole program (or bare
  // statements). It is compiled at once: on an error it is recorded as a
  // kRuntimeException, a RUNTIME_EXCEPTION event is sent and nothing runs;
  // otherwise it replaces the running program (which ends kAborted).
  void SubmitScript(const std::string& text);

  // Dashboard / primary control words. Each returns false when refused.
  bool PowerOn();
  bool PowerOff();
  bool BrakeRelease();
  // Refused (false) before options.protective_stop_unlock_delay_s of
  // simulated time have passed since the stop; true (no-op) when not stopped.
  bool UnlockProtectiveStop();
  // Stops the running program (kAborted); false when none runs.
  bool StopProgram();

  // Halts motion at once, ends the program kProtectiveStop, safety mode
  // PROTECTIVE_STOP; robot mode stays as it was.
  void TriggerProtectiveStop();
  // Fault: while set, every program stalls before its last statement and
  // runs until stopped (a program that never ends).
  void SetHangPrograms(bool hang);
  // Emergency stop: safety mode ROBOT_EMERGENCY_STOP, the arm powered off
  // (program aborted, tool outputs off); `power on` is refused until
  // ResetEmergencyStop, which makes the safety mode NORMAL and leaves the
  // arm POWER_OFF.
  void TriggerEmergencyStop();
  void ResetEmergencyStop();

  RobotSnapshot Snapshot() const;
  std::vector<ExecutedProgram> Programs() const;
  double SimTime() const;

  // Waits until `predicate(snapshot)` holds or `timeout` (wall) passes; true
  // when it holds. The predicate runs under the controller lock: it must
  // not call back into the controller.
  bool WaitFor(const std::function<bool(const RobotSnapshot&)>& predicate,
               absl::Duration timeout) const;

  // Events after `*cursor` (which is advanced), waiting up to `timeout` for
  // at least one. Events older than the last 4096 are dropped.
  std::vector<ControllerEvent> NextEvents(uint64_t* cursor, absl::Duration timeout) const;
  // The cursor of the next event (a new client starts here).
  uint64_t EventCursor() const;

 private:
  enum class Abort { kNone, kReplaced, kStopped, kProtectiveStop, kPowerOff, kShutdown };
  struct Outcome {
    ProgramOutcome outcome = ProgramOutcome::kCompleted;
    std::string error_text;
    int line = 0;
    int column = 0;
  };
  struct Pending {
    std::string text;
    ScriptProgram program;
  };

  void Run();
  void RunProgramLocked(std::unique_lock<std::mutex>& lock, Pending pending);
  // Executes one call; returns an outcome when the program must end.
  std::optional<Outcome> ExecuteLocked(std::unique_lock<std::mutex>& lock, const ScriptCall& call);
  // Moves along q(s) for a profile of `duration` seconds; `sample` gives the
  // joints at simulated time t in [0, duration] or an error text.
  std::optional<Outcome> MoveLocked(
      std::unique_lock<std::mutex>& lock, const ScriptCall& call, double duration,
      const std::function<std::optional<std::string>(double t, ur::Joints& q)>& sample,
      const ur::Joints& final_target);
  // Waits until simulated time `t` or an abort; false on abort.
  bool WaitUntilSimLocked(std::unique_lock<std::mutex>& lock, double t);
  void AdvanceModesLocked();
  void EmitLocked(ControllerEvent event);
  void RecordStepLocked(ExecutedStep step);
  void SetSafetyModeLocked(int mode);
  void TriggerProtectiveStopLocked();
  Outcome AbortOutcomeLocked() const;
  RobotSnapshot SnapshotLocked() const;
  double SimTimeLocked() const;
  std::chrono::steady_clock::time_point WallOf(double sim_time) const;
  Eigen::Isometry3d TcpOf(const ur::Joints& q) const;
  ArmState ArmStateLocked() const;

  const UrEmulatorOptions options_;
  const std::chrono::steady_clock::time_point start_;

  mutable std::mutex mutex_;
  mutable std::condition_variable changed_;  // any state change
  mutable std::condition_variable events_changed_;

  // All guarded by mutex_.
  ur::Joints q_{};
  ur::Joints q_target_{};
  ur::Joints qd_{};
  Eigen::Isometry3d tcp_offset_ = Eigen::Isometry3d::Identity();
  uint32_t tool_outputs_ = 0;
  uint32_t standard_outputs_ = 0;
  uint32_t configurable_outputs_ = 0;
  int robot_mode_ = kRobotModePowerOff;
  int safety_mode_ = kSafetyModeNormal;
  double protective_stop_time_ = 0.0;
  // A scheduled mode change (power on -> IDLE, brake release -> RUNNING).
  std::optional<std::pair<double, int>> mode_change_;
  bool brake_release_requested_ = false;
  bool hang_programs_ = false;
  std::optional<Pending> pending_;
  Abort abort_ = Abort::kNone;
  bool shutdown_ = false;
  bool program_running_ = false;
  std::vector<ExecutedProgram> programs_;
  size_t current_program_ = 0;  // index in programs_ while program_running_
  size_t programs_finished_ = 0;
  std::deque<ControllerEvent> events_;
  uint64_t events_base_ = 0;  // sequence number of events_.front()

  std::thread thread_;
};

}  // namespace cornerpose::ur_emulator
