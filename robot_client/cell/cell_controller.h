// The daemon's main loop: keeps the controller link up, waits for a
// detection from a frame captured after the last move, chooses a box, plans
// the five waypoints, renders the program and runs it, then advances the
// place slot. Stops (and says why) on a protective stop, a lost, silent or
// stale controller link or a lost perception stream, and resumes by itself
// once the condition clears. Faults a person must look at wait for an
// operator's AcknowledgeFault: an emergency stop, a safety fault, a
// power-off (no automatic power-on or brake release) and a pick whose end is
// unknown (its slot is not reused). After any timeout, lost link or
// reconnect the running program is stopped through the dashboard and
// confirmed stopped before anything is planned. Never commands a pose
// outside the workspace (the planner refuses one), never uses a stale frame.
#pragma once

#include <atomic>
#include <condition_variable>
#include <deque>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/time/time.h"
#include "robot_client/cell/cell_state.h"
#include "robot_client/cell/cell_steps.h"
#include "robot_client/cell/perception_subscriber.h"
#include "robot_client/cell/robot_link.h"
#include "robot_client/config/robot_config.h"

namespace cornerpose::robot_client {

struct CellControllerOptions {
  // The longest one pick program may run before the pick counts as failed.
  absl::Duration program_timeout = absl::Seconds(120);
  // Bring-up (power on, brake release) limit; with the stop confirmation it
  // bounds how long a stop signal can wait (the unit allows 20 s).
  absl::Duration bring_up_timeout = absl::Seconds(15);
  // Between attempts to reconnect to the controller, and between checks
  // while stopped.
  absl::Duration retry_interval = absl::Milliseconds(500);
  // How long to wait for a fresh frame before re-checking the robot.
  absl::Duration frame_wait = absl::Milliseconds(500);
  // Picks kept for ListPicks.
  size_t max_records = 100;
};

// Called from the controller's thread.
struct CellCallbacks {
  std::function<void(const PickRecord&)> on_pick;
  // A state change (with the reason when STOPPED).
  std::function<void(const CellStatusSnapshot&)> on_state;
  // Every rendered program (dry run prints them).
  std::function<void(const std::string& name, const std::string& text)> on_program;
  // Why a frame gave no pick, and other notes for the log.
  std::function<void(const std::string& message)> on_note;
};

class CellController {
 public:
  CellController(RobotClientOptions options, CellControllerOptions controller,
                 PerceptionSubscriber* perception, CellCallbacks callbacks = {});

  // Runs until Stop(), or until the pattern is full / max_picks are made.
  void Run();
  // Thread-safe; a running program is stopped through the dashboard (and
  // confirmed stopped, within robot.stop_confirm_timeout_s), its pick marked
  // UNKNOWN, and Run returns.
  void Stop();

  // An operator's acknowledgement (thread-safe; logged through on_note
  // with who and when): allows the next power-on and brake release and
  // clears a pick of unknown end (`unknown_pick_placed`: its box is on its
  // slot, so the slot counts as taken). Returns what was cleared;
  // INVALID_ARGUMENT without an operator, FAILED_PRECONDITION when nothing
  // waits for one.
  absl::StatusOr<std::string> AcknowledgeFault(const std::string& operator_name,
                                               const std::string& note, bool unknown_pick_placed);

  CellStatusSnapshot Status() const;
  // The newest `max` picks (0 = all kept), oldest first.
  std::vector<PickRecord> Picks(size_t max = 0) const;

 private:
  // A planned, rendered pick, ready to run.
  struct PreparedPick {
    PickRecord record;
    std::string program;
  };

  // One pass of the loop, in the phases below; false when the cell is
  // finished.
  bool Step();
  // The newest frame captured after the last move (each judged once), or
  // nullopt (with the state saying why when the stream is down).
  std::optional<FrameDetection> AwaitFreshFrame();
  // Where the arm is (dry run: the clear pose); nullopt without a state.
  std::optional<ur::Joints> CurrentJoints();
  // Selection, planning (the best box that plans) and the program of one
  // frame; nullopt, with a note saying why, when the frame gives no pick.
  std::optional<PreparedPick> PreparePick(const FrameDetection& frame, const ur::Joints& joints,
                                          int slot);
  // Runs the program (dry run: records it) and records the outcome.
  void RunPick(PreparedPick pick);
  void Note(const std::string& message);
  // Whether the robot can take a program now; sets STOPPED and waits when not.
  bool RobotReady();
  // Whether the gripper's suction output is on in `state`.
  bool SuctionOn(const ur::RtdeState& state) const;
  void SetState(CellState state, const std::string& reason = "");
  void Record(PickRecord record);
  // Sleeps up to `d` unless stopped.
  void Pause(absl::Duration d);
  // Stops the program through the dashboard and confirms it; on failure
  // closes the link so the next step reconnects and tries again.
  bool StopProgramNow();
  // STOPPED with `reason`, then a pause; returns false for RobotReady.
  bool Halt(const std::string& reason);

  const RobotClientOptions options_;
  const CellControllerOptions controller_;
  PerceptionSubscriber* const perception_;
  const CellCallbacks callbacks_;
  RobotLink link_;
  const Reachability reachable_;

  mutable std::mutex mutex_;
  std::condition_variable stop_cv_;
  bool stopping_ = false;           // guarded by mutex_
  // Power-on / brake release allowed (once): at start when
  // robot.bring_up_at_start, then after each AcknowledgeFault.
  bool bring_up_allowed_ = false;  // guarded by mutex_
  // An emergency stop or safety fault was seen: wait for an acknowledgement
  // even once the controller reports NORMAL again.
  std::string latched_fault_;  // guarded by mutex_
  // The slot of the pick whose end is unknown (status_.unknown_pick_id).
  int unknown_pick_slot_ = -1;  // guarded by mutex_
  // Grasp depths of the completed picks, oldest first, at most 100: the
  // face check's history (SelectionOptions::face_check_history).
  std::vector<double> picked_depths_;  // guarded by mutex_
  // The grasp point of the last completed pick from a live camera, until
  // the next frame says whether its box left; the picks that left theirs
  // (declined until a pick takes its box). The loop's thread only.
  std::optional<Eigen::Vector3d> last_completed_grasp_;
  std::vector<NotLifted> not_lifted_;
  CellStatusSnapshot status_;       // guarded by mutex_
  std::deque<PickRecord> records_;  // guarded by mutex_

  // Loop state (controller thread only).
  // Frames before this are not used: captured before the end of the last
  // move (the arm may have been in view, the scene has changed) by the
  // server's stamp and by the source's frame order, or already judged.
  FrameFloor floor_;
  uint64_t next_pick_id_ = 1;
  // A program may still run (start, a reconnect, a timeout, a lost link):
  // stop and confirm before planning.
  bool program_check_pending_ = true;
};

}  // namespace cornerpose::robot_client
