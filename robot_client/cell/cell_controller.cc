#include "robot_client/cell/cell_controller.h"

#include <algorithm>
#include <utility>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "robot_client/cell/cell_steps.h"
#include "robot_client/planning/grasp_geometry.h"
#include "robot_client/planning/pick_selection.h"
#include "robot_client/planning/place_pattern.h"
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
  }
  return PickOutcome::kTimeout;
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
      not_before_(absl::Now()) {
  status_.num_slots = SlotCount(options_.place_pattern);
  status_.dry_run = options_.dry_run;
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
    } else {
      ++status_.picks_failed;
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

bool CellController::RobotReady() {
  if (options_.dry_run) return true;
  if (!link_.connected()) {
    link_.Close();
    if (absl::Status s = link_.Connect(); !s.ok()) {
      SetState(CellState::kStopped, absl::StrCat("controller not reachable: ", s.message()));
      Pause(controller_.retry_interval);
      return false;
    }
  }
  if (std::optional<std::string> stop = link_.SafetyStop()) {
    SetState(CellState::kStopped, absl::StrCat(*stop, "; waiting for it to be cleared"));
    Pause(controller_.retry_interval);
    return false;
  }
  absl::StatusOr<ur::RtdeState> state = link_.State();
  if (!state.ok()) {
    SetState(CellState::kStopped, absl::StrCat("no robot state: ", state.status().message()));
    Pause(controller_.retry_interval);
    return false;
  }
  // A pick cut short (a protective stop, say) can leave the vacuum on and a
  // box on the cup; the next program would carry it into the pile. That is
  // for an operator to clear: wait until the output is off.
  if (SuctionOn(*state)) {
    SetState(CellState::kStopped,
             "the suction output is on with no pick running (a box may still be on the "
             "gripper): clear it and switch the output off");
    Pause(controller_.retry_interval);
    return false;
  }
  if (static_cast<ur::RobotMode>(state->robot_mode) != ur::RobotMode::kRunning) {
    SetState(CellState::kStarting, "bringing the arm up (power on, brake release)");
    if (absl::Status s = link_.BringUp(controller_.bring_up_timeout); !s.ok()) {
      SetState(CellState::kStopped, absl::StrCat("bring-up failed: ", s.message()));
      Pause(controller_.retry_interval);
      return false;
    }
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
  std::optional<FrameDetection> frame =
      perception_->WaitForFrameAfter(not_before_, controller_.frame_wait);
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
  not_before_ = std::max(not_before_, frame->capture_time);
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
  // The size the server detected with: it alone resolves model names.
  const BoxDims dims = frame.box_dims.value_or(options_.perception.box);
  const PickSelection selection =
      SelectPick(frame.boxes, options_.base_T_camera, dims, options_.selection, options_.workspace,
                 options_.waypoints, reachable_);
  const std::string frame_name = absl::StrCat(frame.source, "#", frame.frame_id);
  if (!selection.chosen) {
    Note(absl::StrCat(frame_name, ": ", DescribeRejections(selection)));
    return std::nullopt;
  }
  PlannedPick planned = PlanFirstPlannable(selection, [&](const BoxInBase& box) {
    return PlanPickForSlot(options_, joints, box, slot, dims);
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
    not_before_ = absl::Now();
    Record(std::move(record));
    return;
  }
  SetState(CellState::kPicking);
  const ur::ProgramOutcome outcome =
      link_.RunProgram(record.program_name, pick.program, controller_.program_timeout);
  // Every frame captured until now may show the arm or the old scene.
  not_before_ = absl::Now();
  record.program_s = absl::ToDoubleSeconds(not_before_ - record.start_time);
  record.outcome = OutcomeOf(outcome.kind);
  record.detail = outcome.detail;
  if (outcome.kind == ur::ProgramOutcome::kConnectionLost) link_.Close();
  // The primary interface reported the stop; let RTDE catch up so the next
  // step sees it and waits for it to clear instead of sending a program.
  if (outcome.kind == ur::ProgramOutcome::kProtectiveStop) {
    link_.WaitForSafetyStop(absl::Seconds(2));
  }
  Record(std::move(record));
  SetState(CellState::kIdle);
}

void CellController::Note(const std::string& message) {
  if (callbacks_.on_note) callbacks_.on_note(message);
}

}  // namespace cornerpose::robot_client
