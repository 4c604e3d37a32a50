#include "robot_client/cell/cell_controller.h"

#include <algorithm>
#include <utility>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "robot_client/cell/cell_steps.h"
#include "robot_client/planning/grasp_geometry.h"
#include "robot_client/planning/pick_selection.h"
#include "robot_client/planning/place_pattern.h"
#include "robot_client/planning/planning_scene.h"
#include "robot_client/planning/urscript_program.h"
#include "robot_client/ur/dashboard.h"

namespace cornerpose::robot_client {
namespace {

PickOutcome OutcomeOf(ur::ProgramOutcome::Kind kind) {
  switch (kind) {
    case ur::ProgramOutcome::kCompleted:
      return PickOutcome::kCompleted;
    case ur::ProgramOutcome::kRuntimeException:
      return PickOutcome::kRuntimeException;
    case ur::ProgramOutcome::kProtectiveStop:
      return PickOutcome::kProtectiveStop;
    case ur::ProgramOutcome::kConnectionLost:
      return PickOutcome::kConnectionLost;
    case ur::ProgramOutcome::kTimeout:
      return PickOutcome::kTimeout;
    case ur::ProgramOutcome::kUnfinished:
    case ur::ProgramOutcome::kCancelled:
      return PickOutcome::kUnknown;
  }
  return PickOutcome::kUnknown;
}

}  // namespace

CellController::CellController(RobotClientOptions options, CellControllerOptions controller,
                               PerceptionSubscriber* perception, CellCallbacks callbacks)
    : options_(std::move(options)),
      controller_(controller),
      perception_(perception),
      callbacks_(std::move(callbacks)),
      link_(options_.robot),
      reachable_(MakeIkReachability(options_.robot.arm_model, options_.gripper.flange_T_tcp)),
      floor_(perception_->FloorAfterNow()) {
  status_.num_slots = SlotCount(options_.place_pattern);
  status_.dry_run = options_.dry_run;
  bring_up_allowed_ = options_.robot.bring_up_at_start;
}

void CellController::Run() {
  while (true) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (stopping_) break;
    }
    if (!Step()) break;
  }
  link_.Close();
}

void CellController::Stop() {
  std::lock_guard<std::mutex> lock(mutex_);
  stopping_ = true;
  stop_cv_.notify_all();
}

CellStatusSnapshot CellController::Status() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return status_;
}

std::vector<PickRecord> CellController::Picks(size_t max) const {
  std::lock_guard<std::mutex> lock(mutex_);
  const size_t n = max == 0 ? records_.size() : std::min(max, records_.size());
  return std::vector<PickRecord>(records_.end() - static_cast<std::ptrdiff_t>(n), records_.end());
}

void CellController::Pause(absl::Duration d) {
  std::unique_lock<std::mutex> lock(mutex_);
  stop_cv_.wait_for(lock, absl::ToChronoNanoseconds(d), [&] { return stopping_; });
}

void CellController::SetState(CellState state, const std::string& reason) {
  CellStatusSnapshot snapshot;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    status_.perception_connected = perception_->connected();
    status_.robot_connected = options_.dry_run ? false : link_.connected();
    if (status_.state == state && status_.stop_reason == reason) return;
    status_.state = state;
    status_.stop_reason = reason;
    snapshot = status_;
  }
  if (callbacks_.on_state) callbacks_.on_state(snapshot);
}

void CellController::Record(PickRecord record) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (record.outcome == PickOutcome::kCompleted || record.outcome == PickOutcome::kDryRun) {
      ++status_.picks_done;
      ++status_.next_slot;
      picked_depths_.push_back(record.plan.box.depth_m);
      if (record.outcome == PickOutcome::kCompleted && record.source_live) {
        last_completed_grasp_ = record.plan.box.grasp_point;
      }
      if (picked_depths_.size() > 100) picked_depths_.erase(picked_depths_.begin());
    } else {
      ++status_.picks_failed;
    }
    if (record.outcome == PickOutcome::kUnknown) {
      status_.unknown_pick_id = record.pick_id;
      unknown_pick_slot_ = record.plan.slot;
    }
    records_.push_back(record);
    while (records_.size() > controller_.max_records) records_.pop_front();
  }
  if (callbacks_.on_pick) callbacks_.on_pick(record);
}

bool CellController::SuctionOn(const ur::RtdeState& state) const {
  // RTDE's output word: standard outputs in bits 0-7, tool outputs from 16.
  const int bit = options_.gripper.suction_output == SuctionOutputKind::kTool
                      ? 16 + options_.gripper.suction_output_index
                      : options_.gripper.suction_output_index;
  return (state.digital_outputs >> bit) & 1u;
}

bool CellController::Halt(const std::string& reason) {
  SetState(CellState::kStopped, reason);
  Pause(controller_.retry_interval);
  return false;
}

bool CellController::StopProgramNow() {
  if (absl::Status s = link_.StopProgramAndConfirm(); !s.ok()) {
    Note(absl::StrCat("cannot stop the program: ", s.message(), "; reconnecting"));
    link_.Close();
    program_check_pending_ = true;
    return false;
  }
  program_check_pending_ = false;
  return true;
}

absl::StatusOr<std::string> CellController::AcknowledgeFault(const std::string& operator_name,
                                                             const std::string& note,
                                                             bool unknown_pick_placed) {
  if (operator_name.empty()) {
    return absl::InvalidArgumentError("AcknowledgeFault: operator is required");
  }
  std::string cleared;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!status_.awaiting_acknowledgement && status_.unknown_pick_id == 0 &&
        latched_fault_.empty()) {
      return absl::FailedPreconditionError("nothing waits for an acknowledgement");
    }
    bring_up_allowed_ = true;
    if (!latched_fault_.empty()) cleared = latched_fault_;
    latched_fault_.clear();
    if (status_.unknown_pick_id != 0) {
      absl::StrAppend(&cleared, cleared.empty() ? "" : "; ", "pick ", status_.unknown_pick_id,
                      unknown_pick_placed ? " placed: slot " : " not placed: slot ",
                      unknown_pick_slot_, unknown_pick_placed ? " taken" : " used again");
      if (unknown_pick_placed) {
        ++status_.next_slot;
        ++status_.picks_done;
        --status_.picks_failed;
      }
      status_.unknown_pick_id = 0;
      unknown_pick_slot_ = -1;
    }
    if (cleared.empty()) cleared = "power-on and brake release allowed";
    status_.last_acknowledgement =
        absl::StrCat(operator_name, " at ", absl::FormatTime(absl::Now()), ": ", note);
    status_.awaiting_acknowledgement = false;
  }
  Note(absl::StrCat("acknowledged by ", operator_name, " (", note, "): ", cleared));
  stop_cv_.notify_all();
  return cleared;
}

bool CellController::RobotReady() {
  if (options_.dry_run) return true;
  if (!link_.connected()) {
    link_.Close();
    // Whatever ran before the link went is stopped before anything new.
    program_check_pending_ = true;
    if (absl::Status s = link_.Connect(); !s.ok()) {
      return Halt(absl::StrCat("controller not reachable: ", s.message()));
    }
  }
  if (std::optional<std::string> bad = link_.Unhealthy()) {
    // Silent or stale: reconnect (the stale state is never planned from).
    link_.Close();
    program_check_pending_ = true;
    return Halt(absl::StrCat("controller link not trusted: ", *bad));
  }
  if (program_check_pending_ && !StopProgramNow()) {
    return Halt("cannot confirm that no program runs on the controller");
  }
  {
    std::unique_lock<std::mutex> lock(mutex_);
    if (status_.unknown_pick_id != 0) {
      status_.awaiting_acknowledgement = true;
      const std::string reason = absl::StrCat(
          "pick ", status_.unknown_pick_id, " ended unknown; slot ", unknown_pick_slot_,
          " is not reused until an operator says whether its box is there (AcknowledgeFault)");
      lock.unlock();
      return Halt(reason);
    }
  }
  absl::StatusOr<ur::RtdeState> state = link_.State();
  if (!state.ok()) {
    return Halt(absl::StrCat("no robot state: ", state.status().message()));
  }
  const auto safety = static_cast<ur::SafetyMode>(state->safety_mode);
  const bool latching = safety == ur::SafetyMode::kSystemEmergencyStop ||
                        safety == ur::SafetyMode::kRobotEmergencyStop ||
                        safety == ur::SafetyMode::kViolation || safety == ur::SafetyMode::kFault;
  if (latching) {
    std::lock_guard<std::mutex> lock(mutex_);
    latched_fault_ = absl::StrCat("safety mode ", ur::SafetyModeName(safety));
    bring_up_allowed_ = false;
  }
  if (std::optional<std::string> stop = link_.SafetyStop()) {
    return Halt(absl::StrCat(*stop, "; waiting for it to be cleared"));
  }
  {
    std::unique_lock<std::mutex> lock(mutex_);
    if (!latched_fault_.empty()) {
      status_.awaiting_acknowledgement = true;
      const std::string reason =
          absl::StrCat(latched_fault_,
                       " was reset; waiting for an operator's AcknowledgeFault before "
                       "power-on and brake release");
      lock.unlock();
      return Halt(reason);
    }
  }
  // A pick cut short (a protective stop, say) can leave the vacuum on and a
  // box on the cup; the next program would carry it into the pile. That is
  // for an operator to clear: wait until the output is off.
  if (SuctionOn(*state)) {
    return Halt(
        "the suction output is on with no pick running (a box may still be on the "
        "gripper): clear it and switch the output off");
  }
  const auto mode = static_cast<ur::RobotMode>(state->robot_mode);
  if (mode != ur::RobotMode::kRunning) {
    {
      std::unique_lock<std::mutex> lock(mutex_);
      if (!bring_up_allowed_) {
        status_.awaiting_acknowledgement = true;
        const std::string reason = absl::StrCat(
            "robot mode ", ur::RobotModeName(mode),
            ": waiting for an operator's AcknowledgeFault before power-on and brake release");
        lock.unlock();
        return Halt(reason);
      }
    }
    SetState(CellState::kStarting, "bringing the arm up (power on, brake release)");
    if (absl::Status s = link_.BringUp(controller_.bring_up_timeout); !s.ok()) {
      return Halt(absl::StrCat("bring-up failed: ", s.message()));
    }
    std::lock_guard<std::mutex> lock(mutex_);
    // One acknowledgement, one bring-up.
    bring_up_allowed_ = false;
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    status_.awaiting_acknowledgement = false;
  }
  return true;
}

bool CellController::Step() {
  const CellStatusSnapshot now = Status();
  if (std::optional<std::string> finished = FinishedReason(now, options_.max_picks)) {
    SetState(CellState::kFinished, *finished);
    return false;
  }
  if (!RobotReady()) return true;
  std::optional<FrameDetection> frame = AwaitFreshFrame();
  if (!frame) return true;
  std::optional<ur::Joints> joints = CurrentJoints();
  if (!joints) return true;
  std::optional<PreparedPick> pick = PreparePick(*frame, *joints, now.next_slot);
  if (!pick) return true;
  RunPick(*std::move(pick));
  return true;
}

std::optional<FrameDetection> CellController::AwaitFreshFrame() {
  std::optional<FrameDetection> frame = perception_->WaitForFrame(floor_, controller_.frame_wait);
  if (!frame) {
    if (!perception_->connected()) {
      const std::string error = perception_->last_error();
      if (error.empty()) {
        SetState(CellState::kStarting, "waiting for the perception stream");
      } else {
        SetState(CellState::kStopped, absl::StrCat("perception stream lost: ", error));
      }
    }
    return std::nullopt;
  }
  SetState(CellState::kIdle);
  // Judge each frame once.
  floor_.not_before = std::max(floor_.not_before, frame->capture_time);
  return frame;
}

std::optional<ur::Joints> CellController::CurrentJoints() {
  // Dry run: the arm is assumed at the clear pose.
  if (options_.dry_run) return *options_.clear_joints;
  absl::StatusOr<ur::RtdeState> state = link_.State();
  if (!state.ok()) return std::nullopt;
  return state->actual_q;
}

std::optional<CellController::PreparedPick> CellController::PreparePick(const FrameDetection& frame,
                                                                        const ur::Joints& joints,
                                                                        int slot) {
  const absl::Time plan_start = absl::Now();
  // The daemon asks for explicit dimensions; grasp depth and layer heights
  // are planned for them, so a response detected with other ones (or not
  // saying which) is refused.
  const BoxDims dims = options_.perception.box;
  const std::string frame_name = absl::StrCat(frame.source, "#", frame.frame_id);
  // A replay's boxes may not be there: only when allowed, or in a dry run.
  if (!frame.source_live && !options_.perception.allow_replay && !options_.dry_run) {
    SetState(CellState::kStopped,
             absl::StrCat(frame_name, ": refused: source '", frame.source,
                          "' is a replay of recorded frames, not a live camera (set "
                          "perception.allow_replay to pick from it, or dry_run)"));
    return std::nullopt;
  }
  if (!frame.box_dims || ((frame.box_dims->vec() - dims.vec()).cwiseAbs().maxCoeff() > 5e-4)) {
    const std::string used = frame.box_dims
                                 ? absl::StrCat(frame.box_dims->l, " x ", frame.box_dims->b, " x ",
                                                frame.box_dims->h, " m")
                                 : std::string("unknown dimensions");
    SetState(CellState::kStopped,
             absl::StrCat(frame_name, ": refused: detected with ", used, ", not the configured ",
                          dims.l, " x ", dims.b, " x ", dims.h, " m"));
    return std::nullopt;
  }
  std::vector<double> picked_depths;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    picked_depths = picked_depths_;
  }
  PickSelection selection =
      SelectPick(frame.boxes, options_.base_T_camera, dims, options_.selection, options_.workspace,
                 options_.waypoints, reachable_, picked_depths);
  // Did the last pick take its box? A box still at its grasp point was not
  // lifted: its slot is used again, and the box is declined until a pick
  // changes the scene.
  constexpr double kSamePlaceM = 0.02;
  if (last_completed_grasp_) {
    if (StillThere(selection, *last_completed_grasp_, kSamePlaceM)) {
      not_lifted_.push_back({*last_completed_grasp_});
      Note(
          absl::StrFormat("%s: the last pick left its box at (%.3f, %.3f, %.3f): slot %d is "
                          "used again",
                          frame_name, last_completed_grasp_->x(), last_completed_grasp_->y(),
                          last_completed_grasp_->z(), slot - 1));
      std::lock_guard<std::mutex> lock(mutex_);
      if (status_.next_slot > 0) --status_.next_slot;
      slot = status_.next_slot;
    } else {
      not_lifted_.clear();
    }
    last_completed_grasp_.reset();
  }
  DeclineNotLifted(not_lifted_, kSamePlaceM, &selection);
  if (!selection.chosen) {
    Note(absl::StrCat(frame_name, ": ", DescribeRejections(selection)));
    return std::nullopt;
  }
  // Free moves keep clear of the pile this frame shows and of the boxes
  // placed so far.
  std::vector<BoxInBase> seen;
  for (const BoxVerdict& verdict : selection.verdicts) seen.push_back(verdict.box);
  PlanningScene scene =
      ScenePerPick(seen, dims, options_.place_pattern, slot, options_.workspace.min_m.z());
  DropWhatTheArmOccupies(options_.robot.arm_model, options_.gripper.flange_T_tcp, joints,
                         CollisionCheckOptions{}, scene);
  PlannedPick planned = PlanFirstPlannable(selection, [&](const BoxInBase& box) {
    return PlanPickForSlot(options_, joints, box, slot, dims, &scene);
  });
  if (planned.chosen == nullptr) {
    Note(
        absl::StrCat(frame_name, ": cannot plan any box: ", absl::StrJoin(planned.refusals, "; ")));
    return std::nullopt;
  }
  PreparedPick pick;
  PickRecord& record = pick.record;
  record.pick_id = next_pick_id_;
  record.program_name = PickProgramName(static_cast<int>(next_pick_id_));
  record.source = frame.source;
  record.source_live = frame.source_live;
  record.frame_id = frame.frame_id;
  record.capture_time = frame.capture_time;
  record.score = planned.chosen->score;
  record.plan = *planned.plan;
  absl::StatusOr<std::string> program =
      RenderPickProgram(record.program_name, *planned.plan, options_.gripper, options_.motion,
                        *options_.clear_joints);
  record.plan_ms = absl::ToDoubleMilliseconds(absl::Now() - plan_start);
  if (!program.ok()) {
    Note(absl::StrCat(frame_name, ": cannot render the program: ", program.status().message()));
    return std::nullopt;
  }
  ++next_pick_id_;
  pick.program = *std::move(program);
  if (callbacks_.on_program) callbacks_.on_program(record.program_name, pick.program);
  return pick;
}

void CellController::RunPick(PreparedPick pick) {
  PickRecord& record = pick.record;
  record.start_time = absl::Now();
  if (options_.dry_run) {
    record.outcome = PickOutcome::kDryRun;
    floor_ = perception_->FloorAfterNow();
    Record(std::move(record));
    return;
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (stopping_) return;  // not planned to run: no record
  }
  SetState(CellState::kPicking);
  // Polled while the program runs: a stop request or a link lost (silent or
  // stale for read_timeout_s) ends the wait at once (the program is then
  // stopped). A state only a little late does not: the program runs on the
  // controller, and a busy host is not a fault of the pick.
  auto cancel = [this]() -> std::optional<std::string> {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (stopping_) return "the daemon is stopping";
    }
    if (std::optional<std::string> lost = link_.Lost()) {
      return absl::StrCat("controller link lost: ", *lost);
    }
    return std::nullopt;
  };
  const ur::ProgramOutcome outcome =
      link_.RunProgram(record.program_name, pick.program, controller_.program_timeout, cancel);
  record.outcome = OutcomeOf(outcome.kind);
  record.detail = outcome.detail;
  switch (outcome.kind) {
    case ur::ProgramOutcome::kCompleted:
    case ur::ProgramOutcome::kRuntimeException:
    case ur::ProgramOutcome::kProtectiveStop:
      // The controller said how the program ended; still confirm nothing
      // runs before the next one.
      program_check_pending_ = true;
      break;
    case ur::ProgramOutcome::kConnectionLost:
    case ur::ProgramOutcome::kTimeout:
    case ur::ProgramOutcome::kUnfinished:
    case ur::ProgramOutcome::kCancelled:
      // Where the arm and the box are is unknown: stop the program now
      // (or on reconnect) and wait for an operator.
      record.outcome = PickOutcome::kUnknown;
      record.detail = absl::StrCat(ur::ProgramOutcomeName(outcome.kind), ": ", outcome.detail);
      program_check_pending_ = true;
      if (outcome.kind == ur::ProgramOutcome::kConnectionLost) {
        link_.Close();
      } else {
        StopProgramNow();
      }
      break;
  }
  // Every frame captured until now may show the arm or the old scene.
  floor_ = perception_->FloorAfterNow();
  record.program_s = absl::ToDoubleSeconds(floor_.not_before - record.start_time);
  // The primary interface reported the stop; let RTDE catch up so the next
  // step sees it and waits for it to clear instead of sending a program.
  if (outcome.kind == ur::ProgramOutcome::kProtectiveStop) {
    link_.WaitForSafetyStop(absl::Seconds(2));
  }
  const bool unknown = record.outcome == PickOutcome::kUnknown;
  const std::string why = absl::StrCat("pick ", record.pick_id, " ended unknown (", record.detail,
                                       "); waiting for an operator's AcknowledgeFault");
  Record(std::move(record));
  if (unknown) {
    SetState(CellState::kStopped, why);
  } else {
    SetState(CellState::kIdle);
  }
}

void CellController::Note(const std::string& message) {
  if (callbacks_.on_note) callbacks_.on_note(message);
}

}  // namespace cornerpose::robot_client
