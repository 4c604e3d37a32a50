#include "tests/support/ur_emulator/controller.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <utility>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"

namespace cornerpose::ur_emulator {
namespace {

constexpr size_t kMaxEvents = 4096;

// A trapezoidal (or triangular) speed profile over `distance`, as a fraction
// of the way covered at time t.
struct Profile {
  double distance = 0.0;
  double duration = 0.0;
  double accel_time = 0.0;
  double peak_speed = 0.0;

  double Fraction(double t) const {
    if (distance <= 0.0 || duration <= 0.0 || t >= duration) return 1.0;
    if (t <= 0.0) return 0.0;
    const double acc = peak_speed / accel_time;
    double s;
    if (t < accel_time) {
      s = 0.5 * acc * t * t;
    } else if (t < duration - accel_time) {
      s = 0.5 * acc * accel_time * accel_time + peak_speed * (t - accel_time);
    } else {
      const double r = duration - t;
      s = distance - 0.5 * acc * r * r;
    }
    return std::clamp(s / distance, 0.0, 1.0);
  }
};

// `t_override` > 0 fixes the duration (URScript's t argument).
Profile MakeProfile(double distance, double v, double a, double t_override) {
  Profile p;
  p.distance = distance;
  // With t given the move takes t even when there is nowhere to go.
  if (t_override > 0.0) p.duration = t_override;
  if (distance <= 1e-12) return p;
  if (t_override > 0.0) {
    p.accel_time = t_override / 4.0;
    p.peak_speed = distance / (t_override - p.accel_time);
    return p;
  }
  if (distance * a < v * v) {
    p.accel_time = std::sqrt(distance / a);
    p.peak_speed = a * p.accel_time;
    p.duration = 2.0 * p.accel_time;
  } else {
    p.accel_time = v / a;
    p.peak_speed = v;
    p.duration = distance / v + p.accel_time;
  }
  return p;
}

ur::Joints ToJoints(const std::vector<double>& v) {
  ur::Joints q{};
  for (size_t i = 0; i < 6 && i < v.size(); ++i) q[i] = v[i];
  return q;
}

ur::UrPose ToPose(const std::vector<double>& v) {
  ur::UrPose p;
  p.position = Eigen::Vector3d(v[0], v[1], v[2]);
  p.rotation = Eigen::Vector3d(v[3], v[4], v[5]);
  return p;
}

std::string ArgsText(const ScriptCall& call) {
  std::vector<std::string> parts;
  for (const auto& [name, value] : call.args) {
    parts.push_back(absl::StrCat(name, "=", value.ToString()));
  }
  return absl::StrJoin(parts, ", ");
}

}  // namespace

const char* ProgramOutcomeName(ProgramOutcome outcome) {
  switch (outcome) {
    case ProgramOutcome::kRunning:
      return "running";
    case ProgramOutcome::kCompleted:
      return "completed";
    case ProgramOutcome::kAborted:
      return "aborted";
    case ProgramOutcome::kProtectiveStop:
      return "protective_stop";
    case ProgramOutcome::kRuntimeException:
      return "runtime_exception";
    case ProgramOutcome::kRejected:
      return "rejected";
  }
  return "unknown";
}

Controller::Controller(UrEmulatorOptions options)
    : options_(std::move(options)), start_(std::chrono::steady_clock::now()) {
  q_ = options_.initial_joints;
  q_target_ = q_;
  robot_mode_ = options_.start_powered_off ? kRobotModePowerOff : kRobotModeRunning;
  thread_ = std::thread([this] { Run(); });
}

Controller::~Controller() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    shutdown_ = true;
    abort_ = Abort::kShutdown;
  }
  changed_.notify_all();
  events_changed_.notify_all();
  thread_.join();
}

double Controller::SimTimeLocked() const {
  const std::chrono::duration<double> wall = std::chrono::steady_clock::now() - start_;
  return wall.count() * options_.time_scale;
}

double Controller::SimTime() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return SimTimeLocked();
}

std::chrono::steady_clock::time_point Controller::WallOf(double sim_time) const {
  return start_ + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                      std::chrono::duration<double>(sim_time / options_.time_scale));
}

Eigen::Isometry3d Controller::TcpOf(const ur::Joints& q) const {
  return ur::ForwardKinematics(options_.model, q) * tcp_offset_;
}

ArmState Controller::ArmStateLocked() const {
  ArmState state;
  state.time_s = SimTimeLocked();
  state.joints = q_;
  state.base_T_tcp = TcpOf(q_);
  state.flange_T_tcp = tcp_offset_;
  state.tool_outputs = tool_outputs_;
  state.standard_outputs = standard_outputs_;
  if (program_running_) state.program = programs_[current_program_].name;
  return state;
}

void Controller::EmitLocked(ControllerEvent event) {
  event.time_s = SimTimeLocked();
  events_.push_back(std::move(event));
  while (events_.size() > kMaxEvents) {
    events_.pop_front();
    ++events_base_;
  }
  events_changed_.notify_all();
}

void Controller::SetSafetyModeLocked(int mode) {
  if (safety_mode_ == mode) return;
  safety_mode_ = mode;
  ControllerEvent event;
  event.kind = ControllerEvent::Kind::kSafetyMode;
  event.safety_mode = mode;
  EmitLocked(std::move(event));
}

void Controller::AdvanceModesLocked() {
  if (!mode_change_ || SimTimeLocked() < mode_change_->first) return;
  robot_mode_ = mode_change_->second;
  mode_change_.reset();
  if (robot_mode_ == kRobotModeIdle && brake_release_requested_) {
    brake_release_requested_ = false;
    mode_change_ = {SimTimeLocked() + options_.brake_release_delay_s, kRobotModeRunning};
  }
  changed_.notify_all();
}

void Controller::SubmitScript(const std::string& text) {
  ParseResult parsed = ParseScript(text);
  std::lock_guard<std::mutex> lock(mutex_);
  if (parsed.error) {
    ExecutedProgram record;
    record.name = parsed.program.name;
    record.text = text;
    record.outcome = ProgramOutcome::kRuntimeException;
    record.error_text = parsed.error->text;
    record.error_line = parsed.error->line;
    record.error_column = parsed.error->column;
    record.start_time_s = record.end_time_s = SimTimeLocked();
    programs_.push_back(std::move(record));
    ++programs_finished_;
    ControllerEvent event;
    event.kind = ControllerEvent::Kind::kRuntimeException;
    event.text = parsed.error->text;
    event.line = parsed.error->line;
    event.column = parsed.error->column;
    EmitLocked(std::move(event));
    changed_.notify_all();
    return;
  }
  if (pending_) {
    // Replaced before it started: on record as aborted, never run.
    ExecutedProgram record;
    record.name = pending_->program.name;
    record.text = pending_->text;
    record.outcome = ProgramOutcome::kAborted;
    record.start_time_s = record.end_time_s = SimTimeLocked();
    programs_.push_back(std::move(record));
    ++programs_finished_;
  }
  pending_ = Pending{text, std::move(parsed.program)};
  if (program_running_ && abort_ != Abort::kProtectiveStop) abort_ = Abort::kReplaced;
  changed_.notify_all();
}

bool Controller::PowerOn() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (safety_mode_ == kSafetyModeRobotEmergencyStop) return false;
  if (robot_mode_ == kRobotModePowerOff) {
    robot_mode_ = kRobotModePowerOn;
    mode_change_ = {SimTimeLocked() + options_.power_on_delay_s, kRobotModeIdle};
    changed_.notify_all();
  }
  return true;
}

bool Controller::PowerOff() {
  std::lock_guard<std::mutex> lock(mutex_);
  robot_mode_ = kRobotModePowerOff;
  mode_change_.reset();
  brake_release_requested_ = false;
  if (program_running_ && abort_ != Abort::kProtectiveStop) abort_ = Abort::kPowerOff;
  pending_.reset();
  changed_.notify_all();
  return true;
}

bool Controller::BrakeRelease() {
  std::lock_guard<std::mutex> lock(mutex_);
  switch (robot_mode_) {
    case kRobotModePowerOff:
      return false;
    case kRobotModePowerOn:
      brake_release_requested_ = true;
      return true;
    case kRobotModeIdle:
      if (!mode_change_) {
        mode_change_ = {SimTimeLocked() + options_.brake_release_delay_s, kRobotModeRunning};
      }
      changed_.notify_all();
      return true;
    default:
      return true;
  }
}

bool Controller::UnlockProtectiveStop() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (safety_mode_ != kSafetyModeProtectiveStop) return true;
  if (SimTimeLocked() - protective_stop_time_ < options_.protective_stop_unlock_delay_s) {
    return false;
  }
  SetSafetyModeLocked(kSafetyModeNormal);
  changed_.notify_all();
  return true;
}

bool Controller::StopProgram() {
  std::lock_guard<std::mutex> lock(mutex_);
  const bool any = program_running_ || pending_.has_value();
  // A program already halted by a protective stop stays on record as one.
  if (program_running_ && abort_ != Abort::kProtectiveStop) abort_ = Abort::kStopped;
  pending_.reset();
  changed_.notify_all();
  return any;
}

void Controller::TriggerProtectiveStopLocked() {
  if (safety_mode_ == kSafetyModeProtectiveStop) return;
  protective_stop_time_ = SimTimeLocked();
  SetSafetyModeLocked(kSafetyModeProtectiveStop);
  if (program_running_) abort_ = Abort::kProtectiveStop;
  pending_.reset();
  qd_ = {};
  q_target_ = q_;
  changed_.notify_all();
}

void Controller::TriggerProtectiveStop() {
  std::lock_guard<std::mutex> lock(mutex_);
  TriggerProtectiveStopLocked();
}

void Controller::SetHangPrograms(bool hang) {
  std::lock_guard<std::mutex> lock(mutex_);
  hang_programs_ = hang;
  changed_.notify_all();
}

void Controller::TriggerEmergencyStop() {
  std::lock_guard<std::mutex> lock(mutex_);
  SetSafetyModeLocked(kSafetyModeRobotEmergencyStop);
  // The arm loses power: motion, the scheduled mode change and the tool
  // outputs go with it.
  robot_mode_ = kRobotModePowerOff;
  mode_change_.reset();
  brake_release_requested_ = false;
  tool_outputs_ = 0;
  // A program already halted by a protective stop stays on record as one.
  if (program_running_ && abort_ != Abort::kProtectiveStop) abort_ = Abort::kStopped;
  pending_.reset();
  qd_ = {};
  q_target_ = q_;
  changed_.notify_all();
}

void Controller::ResetEmergencyStop() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (safety_mode_ != kSafetyModeRobotEmergencyStop) return;
  // As on the real controller: NORMAL again, but still powered off.
  SetSafetyModeLocked(kSafetyModeNormal);
  changed_.notify_all();
}

RobotSnapshot Controller::SnapshotLocked() const {
  RobotSnapshot s;
  s.time_s = SimTimeLocked();
  s.joints = q_;
  s.target_joints = q_target_;
  s.joint_speeds = qd_;
  s.tcp = ur::ToUrPose(TcpOf(q_));
  s.target_tcp = ur::ToUrPose(TcpOf(q_target_));
  s.tcp_offset = ur::ToUrPose(tcp_offset_);
  s.tool_outputs = tool_outputs_;
  s.standard_outputs = standard_outputs_;
  s.configurable_outputs = configurable_outputs_;
  s.robot_mode = robot_mode_;
  s.safety_mode = safety_mode_;
  s.program_running = program_running_;
  if (program_running_) {
    s.program_name = programs_[current_program_].name;
  } else if (!programs_.empty()) {
    s.program_name = programs_.back().name;
  }
  s.programs_recorded = programs_.size();
  s.programs_finished = programs_finished_;
  return s;
}

RobotSnapshot Controller::Snapshot() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return SnapshotLocked();
}

std::vector<ExecutedProgram> Controller::Programs() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return programs_;
}

bool Controller::WaitFor(const std::function<bool(const RobotSnapshot&)>& predicate,
                         absl::Duration timeout) const {
  const auto deadline = std::chrono::steady_clock::now() + absl::ToChronoNanoseconds(timeout);
  std::unique_lock<std::mutex> lock(mutex_);
  while (true) {
    if (predicate(SnapshotLocked())) return true;
    // Mode changes are scheduled in simulated time; wake at least every
    // 5 ms of wall time so they are seen without a notification.
    const auto next =
        std::min(deadline, std::chrono::steady_clock::now() + std::chrono::milliseconds(5));
    if (std::chrono::steady_clock::now() >= deadline) return false;
    changed_.wait_until(lock, next);
  }
}

uint64_t Controller::EventCursor() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return events_base_ + events_.size();
}

std::vector<ControllerEvent> Controller::NextEvents(uint64_t* cursor,
                                                    absl::Duration timeout) const {
  std::unique_lock<std::mutex> lock(mutex_);
  events_changed_.wait_for(lock, absl::ToChronoNanoseconds(timeout),
                           [&] { return shutdown_ || events_base_ + events_.size() > *cursor; });
  if (*cursor < events_base_) *cursor = events_base_;
  std::vector<ControllerEvent> out;
  for (uint64_t i = *cursor; i < events_base_ + events_.size(); ++i) {
    out.push_back(events_[i - events_base_]);
  }
  *cursor = events_base_ + events_.size();
  return out;
}

void Controller::Run() {
  std::unique_lock<std::mutex> lock(mutex_);
  while (!shutdown_) {
    AdvanceModesLocked();
    if (pending_) {
      Pending pending = std::move(*pending_);
      pending_.reset();
      abort_ = Abort::kNone;
      RunProgramLocked(lock, std::move(pending));
      continue;
    }
    auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(50);
    if (mode_change_) deadline = std::min(deadline, WallOf(mode_change_->first));
    changed_.wait_until(lock, deadline);
  }
}

bool Controller::WaitUntilSimLocked(std::unique_lock<std::mutex>& lock, double t) {
  const auto deadline = WallOf(t);
  while (true) {
    if (abort_ != Abort::kNone || shutdown_) return false;
    AdvanceModesLocked();
    if (std::chrono::steady_clock::now() >= deadline) return true;
    changed_.wait_until(lock, deadline);
  }
}

Controller::Outcome Controller::AbortOutcomeLocked() const {
  Outcome outcome;
  outcome.outcome =
      abort_ == Abort::kProtectiveStop ? ProgramOutcome::kProtectiveStop : ProgramOutcome::kAborted;
  return outcome;
}

void Controller::RecordStepLocked(ExecutedStep step) {
  step.joints = q_;
  step.tcp = ur::ToUrPose(TcpOf(q_));
  step.tool_outputs = tool_outputs_;
  step.standard_outputs = standard_outputs_;
  step.configurable_outputs = configurable_outputs_;
  step.end_time_s = SimTimeLocked();
  programs_[current_program_].steps.push_back(std::move(step));
}

void Controller::RunProgramLocked(std::unique_lock<std::mutex>& lock, Pending pending) {
  ExecutedProgram record;
  record.name = pending.program.name;
  record.text = std::move(pending.text);
  record.start_time_s = SimTimeLocked();
  if (robot_mode_ != kRobotModeRunning || safety_mode_ != kSafetyModeNormal) {
    record.outcome = ProgramOutcome::kRejected;
    record.error_text = robot_mode_ != kRobotModeRunning ? "runtime_error_robot_not_running:"
                                                         : "runtime_error_safety_stop_active:";
    record.end_time_s = record.start_time_s;
    ControllerEvent event;
    event.kind = ControllerEvent::Kind::kRuntimeException;
    event.text = record.error_text;
    EmitLocked(std::move(event));
    programs_.push_back(std::move(record));
    ++programs_finished_;
    changed_.notify_all();
    return;
  }
  programs_.push_back(std::move(record));
  current_program_ = programs_.size() - 1;
  program_running_ = true;
  if (options_.world) options_.world->OnProgramStart(pending.program.name, SimTimeLocked());
  {
    ControllerEvent event;
    event.kind = ControllerEvent::Kind::kProgramStarted;
    event.text = pending.program.name;
    EmitLocked(std::move(event));
  }
  changed_.notify_all();

  Outcome outcome;
  for (size_t i = 0; i < pending.program.calls.size(); ++i) {
    const ScriptCall& call = pending.program.calls[i];
    // Fault: a program that never ends stalls before its last statement
    // (the daemon's done message) until it is stopped or the fault cleared.
    if (i + 1 == pending.program.calls.size()) {
      changed_.wait(lock, [&] { return !hang_programs_ || abort_ != Abort::kNone || shutdown_; });
    }
    if (abort_ != Abort::kNone) {
      outcome = AbortOutcomeLocked();
      break;
    }
    if (auto result = ExecuteLocked(lock, call)) {
      outcome = *result;
      break;
    }
  }

  ExecutedProgram& done = programs_[current_program_];
  done.outcome = outcome.outcome;
  done.error_text = outcome.error_text;
  done.error_line = outcome.line;
  done.error_column = outcome.column;
  done.end_time_s = SimTimeLocked();
  const std::string name = done.name;  // programs_ may grow while unlocked
  const double end_time_s = done.end_time_s;
  if (options_.world) {
    // Without the lock: the world may wait for its camera.
    lock.unlock();
    options_.world->OnProgramEnd(name, outcome.outcome == ProgramOutcome::kCompleted,
                                 end_time_s);
    lock.lock();
  }
  program_running_ = false;
  ++programs_finished_;
  qd_ = {};
  q_target_ = q_;
  if (outcome.outcome == ProgramOutcome::kRuntimeException) {
    ControllerEvent event;
    event.kind = ControllerEvent::Kind::kRuntimeException;
    event.text = outcome.error_text;
    event.line = outcome.line;
    event.column = outcome.column;
    EmitLocked(std::move(event));
  }
  ControllerEvent stopped;
  stopped.kind = ControllerEvent::Kind::kProgramStopped;
  stopped.text = name;
  EmitLocked(std::move(stopped));
  if (abort_ != Abort::kShutdown) abort_ = Abort::kNone;
  changed_.notify_all();
}

std::optional<Controller::Outcome> Controller::MoveLocked(
    std::unique_lock<std::mutex>& lock, const ScriptCall& call, double duration,
    const std::function<std::optional<std::string>(double t, ur::Joints& q)>& sample,
    const ur::Joints& final_target) {
  ExecutedStep step;
  step.kind = call.function;
  step.line = call.line;
  step.args = ArgsText(call);
  step.target = ur::ToUrPose(TcpOf(final_target));
  const double t0 = SimTimeLocked();
  step.start_time_s = t0;
  q_target_ = final_target;
  const double dt = options_.control_period_s;
  for (int k = 1;; ++k) {
    const double t = std::min(k * dt, duration);
    if (!WaitUntilSimLocked(lock, t0 + t)) {
      qd_ = {};
      q_target_ = q_;
      step.completed = false;
      RecordStepLocked(std::move(step));
      return AbortOutcomeLocked();
    }
    ur::Joints q;
    if (auto error = sample(t, q)) {
      qd_ = {};
      q_target_ = q_;
      step.completed = false;
      RecordStepLocked(std::move(step));
      return Outcome{ProgramOutcome::kRuntimeException, *error, call.line, call.column};
    }
    for (int i = 0; i < 6; ++i) qd_[i] = (q[i] - q_[i]) / dt;
    q_ = q;
    changed_.notify_all();
    if (options_.world) {
      if (std::optional<std::string> contact = options_.world->OnStep(ArmStateLocked())) {
        // A collision: the arm stops where it touched, as a real arm's
        // collision detection stops it (protective stop).
        step.completed = false;
        RecordStepLocked(std::move(step));
        ControllerEvent event;
        event.kind = ControllerEvent::Kind::kText;
        event.text = absl::StrCat("protective stop: collision: ", *contact);
        EmitLocked(std::move(event));
        TriggerProtectiveStopLocked();
        return AbortOutcomeLocked();
      }
    }
    if (t >= duration) break;
  }
  qd_ = {};
  RecordStepLocked(std::move(step));
  return std::nullopt;
}

std::optional<Controller::Outcome> Controller::ExecuteLocked(std::unique_lock<std::mutex>& lock,
                                                             const ScriptCall& call) {
  const std::string& f = call.function;
  auto error = [&](std::string text) {
    return Outcome{ProgramOutcome::kRuntimeException, std::move(text), call.line, call.column};
  };
  ExecutedStep step;
  step.kind = f;
  step.line = call.line;
  step.args = ArgsText(call);
  step.start_time_s = SimTimeLocked();

  if (f == "movej" || f == "movel") {
    const ScriptValue& target = call.arg(f == "movej" ? "q" : "pose");
    const double a = call.arg("a").number;
    const double v = call.arg("v").number;
    const double t = call.arg("t").number;
    if (t <= 0.0 && (a <= 0.0 || v <= 0.0)) {
      return error(absl::StrCat("runtime_error_invalid_speed:", f, ":"));
    }
    const ur::Joints q0 = q_;
    if (f == "movej") {
      ur::Joints q1;
      if (target.kind == ScriptValue::Kind::kPose) {
        const Eigen::Isometry3d flange =
            ur::FromUrPose(ToPose(target.elements)) * tcp_offset_.inverse();
        auto ik = ur::InverseKinematics(options_.model, flange, q_);
        if (!ik.ok()) {
          return error(absl::StrCat(
              "runtime_error_inverse_kinematics_failed:movej:", target.ToString(), ":"));
        }
        q1 = *ik;
      } else {
        q1 = ToJoints(target.elements);
        for (double qi : q1) {
          if (std::fabs(qi) > 2.0 * M_PI + 1e-9) {
            return error("runtime_error_joint_limit:movej:");
          }
        }
      }
      double distance = 0.0;
      for (int i = 0; i < 6; ++i) distance = std::max(distance, std::fabs(q1[i] - q0[i]));
      const Profile profile = MakeProfile(distance, std::min(v, options_.max_joint_speed),
                                          std::min(a, options_.max_joint_accel), t);
      return MoveLocked(
          lock, call, profile.duration,
          [&](double time, ur::Joints& q) -> std::optional<std::string> {
            const double s = profile.Fraction(time);
            for (int i = 0; i < 6; ++i) q[i] = q0[i] + s * (q1[i] - q0[i]);
            return std::nullopt;
          },
          q1);
    }

    // movel: a straight line of the TCP, rotation by slerp.
    const Eigen::Isometry3d start = TcpOf(q0);
    const Eigen::Isometry3d goal = target.kind == ScriptValue::Kind::kPose
                                       ? ur::FromUrPose(ToPose(target.elements))
                                       : TcpOf(ToJoints(target.elements));
    const Eigen::Isometry3d tcp_inverse = tcp_offset_.inverse();
    auto final_ik = ur::InverseKinematics(options_.model, goal * tcp_inverse, q0);
    if (!final_ik.ok()) {
      return error(absl::StrCat("runtime_error_inverse_kinematics_failed:movel:",
                                ur::FormatPoseLiteral(ur::ToUrPose(goal)), ":"));
    }
    const Eigen::Quaterniond r0(start.linear());
    const Eigen::Quaterniond r1(goal.linear());
    const double length = (goal.translation() - start.translation()).norm();
    const double angle = ur::RotationAngleBetween(r0, r1);
    const Profile linear = MakeProfile(length, std::min(v, options_.max_tool_speed),
                                       std::min(a, options_.max_tool_accel), t);
    // Rotation at movej's default joint speed / acceleration.
    const Profile angular = MakeProfile(angle, 1.05, 1.4, t);
    const Profile& profile = angular.duration > linear.duration ? angular : linear;
    ur::Joints previous = q0;
    const double max_step = options_.max_joint_step_rad;
    std::optional<ur::Joints> last;
    return MoveLocked(
        lock, call, profile.duration,
        [&](double time, ur::Joints& q) -> std::optional<std::string> {
          const double s = profile.Fraction(time);
          Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
          pose.translation() = start.translation() + s * (goal.translation() - start.translation());
          pose.linear() = r0.slerp(s, r1).toRotationMatrix();
          auto ik = ur::InverseKinematics(options_.model, pose * tcp_inverse, previous);
          if (!ik.ok()) {
            return absl::StrCat("runtime_error_inverse_kinematics_failed:movel:",
                                ur::FormatPoseLiteral(ur::ToUrPose(pose)), ":");
          }
          for (int i = 0; i < 6; ++i) {
            if (std::fabs((*ik)[i] - previous[i]) > max_step) {
              return absl::StrCat("runtime_error_movel_joint_jump:",
                                  ur::FormatPoseLiteral(ur::ToUrPose(pose)), ":");
            }
          }
          previous = *ik;
          q = *ik;
          return std::nullopt;
        },
        *final_ik);
  }

  if (f == "set_tool_digital_out" || f == "set_standard_digital_out" || f == "set_digital_out" ||
      f == "set_configurable_digital_out") {
    const int n = static_cast<int>(call.arg("n").number);
    const bool b = call.arg("b").boolean;
    uint32_t* bits = f == "set_tool_digital_out"           ? &tool_outputs_
                     : f == "set_configurable_digital_out" ? &configurable_outputs_
                                                           : &standard_outputs_;
    if (b) {
      *bits |= 1u << n;
    } else {
      *bits &= ~(1u << n);
    }
    if (options_.world) options_.world->OnOutputs(ArmStateLocked());
    changed_.notify_all();
    RecordStepLocked(std::move(step));
    return std::nullopt;
  }

  if (f == "sleep" || f == "sync") {
    const double duration = f == "sleep" ? call.arg("t").number : options_.control_period_s;
    if (!WaitUntilSimLocked(lock, step.start_time_s + duration)) {
      step.completed = false;
      RecordStepLocked(std::move(step));
      return AbortOutcomeLocked();
    }
    RecordStepLocked(std::move(step));
    return std::nullopt;
  }

  if (f == "textmsg") {
    ControllerEvent event;
    event.kind = ControllerEvent::Kind::kText;
    event.text = call.arg("s1").ToString() + call.arg("s2").ToString();
    EmitLocked(std::move(event));
    RecordStepLocked(std::move(step));
    return std::nullopt;
  }

  if (f == "set_tcp") {
    tcp_offset_ = ur::FromUrPose(ToPose(call.arg("pose").elements));
    q_target_ = q_;
    changed_.notify_all();
    RecordStepLocked(std::move(step));
    return std::nullopt;
  }

  if (f == "protective_stop") {
    RecordStepLocked(std::move(step));
    TriggerProtectiveStopLocked();
    return AbortOutcomeLocked();
  }

  // set_payload, stopl, stopj (the arm is at rest between blocking moves),
  // socket_*: recorded only. socket_open has no network here: the script
  // sees no connection, as when the address is unreachable.
  RecordStepLocked(std::move(step));
  return std::nullopt;
}

}  // namespace cornerpose::ur_emulator
