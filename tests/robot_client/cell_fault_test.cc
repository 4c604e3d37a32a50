// The cell under the faults of issue 12, each injected into the UR
// controller emulator while the daemon drives it over real TCP: a stalled
// RTDE stream, links that stay open but go silent, a program that never
// ends, a program stopped from outside, an emergency stop and its reset, an
// operator's power-off, and SIGTERM to the real daemon process mid-pick.
// Each asserts that no program reaches the arm while the condition holds,
// and that the daemon says why it stopped.
#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "tests/robot_client/cell_fixture.h"

namespace cornerpose::robot_client {
namespace {

using ur_emulator::ProgramOutcome;
using ur_emulator::RobotSnapshot;

class CellFaultTest : public testing::CellFixture {
 protected:
  bool WaitForState(v1::CellState state, const std::string& reason_part, absl::Duration timeout,
                    v1::CellStatus* last) {
    return WaitForStatus(
        [&](const v1::CellStatus& s) {
          return s.state() == state && s.stop_reason().find(reason_part) != std::string::npos;
        },
        timeout, last);
  }
  bool WaitFinished(v1::CellStatus* last) {
    return WaitForStatus(
        [](const v1::CellStatus& s) { return s.state() == v1::CELL_STATE_FINISHED; },
        absl::Seconds(120), last);
  }
};

TEST_F(CellFaultTest, RtdeStallMidPickStopsTheProgramAndWaitsForTheOperator) {
  options_.max_picks = 1;
  // The program waits before its done message, so that it still runs when
  // the stall has lasted read_timeout_s (a pick at the emulator's pace ends
  // sooner, and a pick that ends is reported by the primary interface).
  emulator_->SetHangPrograms(true);
  StartCell();
  ASSERT_TRUE(WaitForProgramRunning(absl::Seconds(60)));
  emulator_->SetRtdeStalled(true);
  v1::CellStatus status;
  // The stream stays stale while the program runs; the program is stopped
  // through the dashboard (which still answers).
  ASSERT_TRUE(WaitForState(v1::CELL_STATE_STOPPED, "RTDE", absl::Seconds(20), &status))
      << status.DebugString();
  ASSERT_TRUE(emulator_->WaitFor([](const RobotSnapshot& s) { return !s.program_running; },
                                 absl::Seconds(5)));
  EXPECT_EQ(emulator_->Programs().at(0).outcome, ProgramOutcome::kAborted);
  // Stalled: nothing is sent.
  EXPECT_TRUE(NoProgramSentFor(absl::Seconds(2)));
  EXPECT_EQ(GetStatus().state(), v1::CELL_STATE_STOPPED);

  // The stream comes back; the pick's end is unknown, so the cell still
  // waits, now for an operator.
  emulator_->SetHangPrograms(false);
  emulator_->SetRtdeStalled(false);
  ASSERT_TRUE(WaitForState(v1::CELL_STATE_STOPPED, "AcknowledgeFault", absl::Seconds(20), &status))
      << status.DebugString();
  EXPECT_TRUE(status.awaiting_acknowledgement());
  EXPECT_EQ(status.unknown_pick_id(), 1u);
  EXPECT_TRUE(NoProgramSentFor(absl::Seconds(1)));
  std::vector<v1::PickRecord> picks = ListPicks();
  ASSERT_EQ(picks.size(), 1u);
  EXPECT_EQ(picks[0].outcome(), v1::PICK_OUTCOME_UNKNOWN) << picks[0].detail();

  EXPECT_EQ(Acknowledge("", false).error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  ASSERT_TRUE(Acknowledge("ada", /*unknown_pick_placed=*/false).ok());
  ASSERT_TRUE(WaitFinished(&status)) << status.DebugString() << PicksText();
  EXPECT_EQ(status.picks_done(), 1u);
  EXPECT_NE(status.last_acknowledgement().find("ada"), std::string::npos);
  picks = ListPicks();
  ASSERT_EQ(picks.size(), 2u);
  // The box was not placed: its slot is used again.
  EXPECT_EQ(picks[1].slot(), 0u);
  EXPECT_EQ(picks[1].outcome(), v1::PICK_OUTCOME_COMPLETED);
}

TEST_F(CellFaultTest, ABriefRtdeHiccupDoesNotCutAPickShort) {
  options_.max_picks = 1;
  StartCell();
  ASSERT_TRUE(WaitForProgramRunning(absl::Seconds(60)));
  // Packages a few hundred milliseconds late (a busy host): older than
  // rtde_max_age_s, well within read_timeout_s. The program runs on.
  emulator_->SetRtdeStalled(true);
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  emulator_->SetRtdeStalled(false);
  v1::CellStatus status;
  ASSERT_TRUE(WaitFinished(&status)) << status.DebugString() << PicksText();
  EXPECT_EQ(status.picks_done(), 1u);
  EXPECT_EQ(status.picks_failed(), 0u);
  ASSERT_EQ(emulator_->Programs().size(), 1u);
  EXPECT_EQ(emulator_->Programs()[0].outcome, ProgramOutcome::kCompleted);
}

TEST_F(CellFaultTest, SilentLinksStopTheCellUntilTheyTalkAgain) {
  options_.max_picks = 1;
  StartCell();
  ASSERT_TRUE(WaitForProgramRunning(absl::Seconds(60)));
  emulator_->SetLinksSilent(true);
  v1::CellStatus status;
  ASSERT_TRUE(WaitForState(v1::CELL_STATE_STOPPED, "", absl::Seconds(10), &status))
      << status.DebugString();
  // Open but silent (and every reconnect as silent): nothing new is sent.
  const size_t sent = emulator_->Snapshot().programs_recorded;
  EXPECT_TRUE(NoProgramSentFor(absl::Seconds(3)));
  EXPECT_EQ(GetStatus().state(), v1::CELL_STATE_STOPPED);
  EXPECT_EQ(emulator_->Snapshot().programs_recorded, sent);

  emulator_->SetLinksSilent(false);
  ASSERT_TRUE(WaitForState(v1::CELL_STATE_STOPPED, "AcknowledgeFault", absl::Seconds(30), &status))
      << status.DebugString();
  EXPECT_EQ(emulator_->Snapshot().programs_recorded, sent);
  ASSERT_TRUE(Acknowledge("ada", false).ok());
  ASSERT_TRUE(WaitFinished(&status)) << status.DebugString() << PicksText();
  EXPECT_EQ(status.picks_done(), 1u);
}

TEST_F(CellFaultTest, ProgramThatNeverEndsIsStoppedAndItsSlotKept) {
  options_.max_picks = 1;
  program_timeout_ = absl::Seconds(4);
  emulator_->SetHangPrograms(true);
  StartCell();
  v1::CellStatus status;
  ASSERT_TRUE(WaitForState(v1::CELL_STATE_STOPPED, "AcknowledgeFault", absl::Seconds(60), &status))
      << status.DebugString();
  // The daemon stopped it (dashboard) and saw it stopped.
  RobotSnapshot snapshot = emulator_->Snapshot();
  EXPECT_FALSE(snapshot.program_running);
  ASSERT_EQ(emulator_->Programs().size(), 1u);
  EXPECT_EQ(emulator_->Programs()[0].outcome, ProgramOutcome::kAborted);
  std::vector<v1::PickRecord> picks = ListPicks();
  ASSERT_EQ(picks.size(), 1u);
  EXPECT_EQ(picks[0].outcome(), v1::PICK_OUTCOME_UNKNOWN);
  EXPECT_NE(picks[0].detail().find("timeout"), std::string::npos) << picks[0].detail();
  EXPECT_TRUE(NoProgramSentFor(absl::Seconds(1)));

  // The operator found the box on its slot: the slot is taken.
  emulator_->SetHangPrograms(false);
  ASSERT_TRUE(Acknowledge("grace", /*unknown_pick_placed=*/true).ok());
  ASSERT_TRUE(WaitFinished(&status)) << status.DebugString() << PicksText();
  EXPECT_EQ(status.picks_done(), 1u);  // the acknowledged one counts as placed
  EXPECT_EQ(status.next_slot(), 1u);
  EXPECT_EQ(ListPicks().size(), 1u);  // max_picks was reached by it
}

TEST_F(CellFaultTest, ProgramStoppedFromOutsideIsUnknownNotCompleted) {
  options_.max_picks = 2;
  StartCell();
  ASSERT_TRUE(WaitForProgramRunning(absl::Seconds(60)));
  // Someone presses stop on the pendant: PROGRAM_XXX_STOPPED, no done
  // message.
  ASSERT_TRUE(emulator_->controller().StopProgram());
  v1::CellStatus status;
  ASSERT_TRUE(WaitForState(v1::CELL_STATE_STOPPED, "AcknowledgeFault", absl::Seconds(20), &status))
      << status.DebugString();
  EXPECT_EQ(status.picks_done(), 0u);
  std::vector<v1::PickRecord> picks = ListPicks();
  ASSERT_EQ(picks.size(), 1u);
  EXPECT_EQ(picks[0].outcome(), v1::PICK_OUTCOME_UNKNOWN);
  EXPECT_NE(picks[0].detail().find("done message"), std::string::npos) << picks[0].detail();
  EXPECT_TRUE(NoProgramSentFor(absl::Seconds(1)));
  ASSERT_TRUE(Acknowledge("ada", false).ok());
  ASSERT_TRUE(WaitFinished(&status)) << status.DebugString() << PicksText();
  EXPECT_EQ(status.picks_done(), 2u);
}

TEST_F(CellFaultTest, EmergencyStopNeedsAnAcknowledgementBeforePowerOn) {
  options_.max_picks = 1;
  StartCell();
  ASSERT_TRUE(WaitForProgramRunning(absl::Seconds(60)));
  emulator_->TriggerEmergencyStop();
  v1::CellStatus status;
  ASSERT_TRUE(WaitForState(v1::CELL_STATE_STOPPED, "EMERGENCY", absl::Seconds(10), &status))
      << status.DebugString();
  EXPECT_TRUE(NoProgramSentFor(absl::Seconds(1)));

  // Reset on the cell: the controller is NORMAL and powered off, and the
  // daemon does not power it on by itself.
  emulator_->ResetEmergencyStop();
  ASSERT_TRUE(WaitForState(v1::CELL_STATE_STOPPED, "AcknowledgeFault", absl::Seconds(10), &status))
      << status.DebugString();
  EXPECT_TRUE(NoProgramSentFor(absl::Seconds(2)));
  EXPECT_EQ(emulator_->Snapshot().robot_mode, ur_emulator::kRobotModePowerOff);
  EXPECT_TRUE(status.awaiting_acknowledgement());

  v1::AcknowledgeFaultResponse response;
  ASSERT_TRUE(Acknowledge("ada", false, &response).ok());
  EXPECT_NE(response.cleared().find("EMERGENCY"), std::string::npos) << response.cleared();
  ASSERT_TRUE(WaitFinished(&status)) << status.DebugString() << PicksText();
  EXPECT_EQ(status.picks_done(), 1u);
}

TEST_F(CellFaultTest, OperatorPowerOffIsNotUndoneByTheDaemon) {
  options_.max_picks = 1;
  StartCell();
  ASSERT_TRUE(WaitForProgramRunning(absl::Seconds(60)));
  ASSERT_TRUE(emulator_->controller().PowerOff());
  v1::CellStatus status;
  ASSERT_TRUE(WaitForState(v1::CELL_STATE_STOPPED, "AcknowledgeFault", absl::Seconds(20), &status))
      << status.DebugString();
  EXPECT_TRUE(NoProgramSentFor(absl::Seconds(2)));
  EXPECT_EQ(emulator_->Snapshot().robot_mode, ur_emulator::kRobotModePowerOff);
  // Nothing to acknowledge is refused only when nothing waits; here the
  // acknowledgement clears the unknown pick and allows the bring-up.
  ASSERT_TRUE(Acknowledge("ada", false).ok());
  ASSERT_TRUE(WaitFinished(&status)) << status.DebugString() << PicksText();
  EXPECT_EQ(status.picks_done(), 1u);
  EXPECT_EQ(Acknowledge("ada", false).error_code(), grpc::StatusCode::FAILED_PRECONDITION);
}

TEST_F(CellFaultTest, NoBringUpAtStartUnlessConfigured) {
  options_.max_picks = 1;
  options_.robot.bring_up_at_start = false;
  StartCell();
  v1::CellStatus status;
  ASSERT_TRUE(WaitForState(v1::CELL_STATE_STOPPED, "POWER_OFF", absl::Seconds(20), &status))
      << status.DebugString();
  EXPECT_TRUE(NoProgramSentFor(absl::Seconds(1)));
  EXPECT_EQ(emulator_->Snapshot().robot_mode, ur_emulator::kRobotModePowerOff);
  ASSERT_TRUE(Acknowledge("ada", false).ok());
  ASSERT_TRUE(WaitFinished(&status)) << status.DebugString() << PicksText();
}

// Recorded frames are a replay: without allow_replay (and not a dry run)
// the cell refuses them, names the source, and sends the arm nothing.
TEST_F(CellFaultTest, ReplaySourceIsRefusedUnlessAllowed) {
  options_.max_picks = 1;
  options_.perception.allow_replay = false;
  StartCell();
  v1::CellStatus status;
  ASSERT_TRUE(
      WaitForState(v1::CELL_STATE_STOPPED, "'cell' is a replay", absl::Seconds(30), &status))
      << status.DebugString();
  EXPECT_TRUE(NoProgramSentFor(absl::Seconds(2)));
  EXPECT_EQ(status.picks_done(), 0u);
}

// The server detected with other dimensions than the cell plans for (here
// the subscription asks for another size): every frame is refused, the
// reason names both sizes, and no program is sent.
TEST_F(CellFaultTest, DetectionsOfAnotherBoxSizeAreRefused) {
  options_.max_picks = 1;
  subscribed_box_ = BoxDims{0.32, 0.20, 0.15};
  StartCell();
  v1::CellStatus status;
  ASSERT_TRUE(WaitForState(v1::CELL_STATE_STOPPED, "not the configured 0.3 x 0.2 x 0.15 m",
                           absl::Seconds(30), &status))
      << status.DebugString();
  EXPECT_NE(status.stop_reason().find("0.32 x 0.2 x 0.15 m"), std::string::npos)
      << status.stop_reason();
  EXPECT_TRUE(NoProgramSentFor(absl::Seconds(2)));
  EXPECT_EQ(status.picks_done(), 0u);
}

// The real daemon binary: SIGTERM mid-pick stops the arm's program and
// exits 0 well inside the systemd unit's TimeoutStopSec (20 s).
TEST_F(CellFaultTest, SigtermMidPickStopsTheProgramAndExits) {
  const std::string log_path = ::testing::TempDir() + "/robot_client_sigterm.log";
  const std::vector<std::string> args = {
      CORNERPOSE_ROBOT_CLIENT_BINARY,
      "--config=" + testing::ShippedCellConfig(),
      "--server=" + options_.perception.server_address,
      "--source=cell",
      "--robot_host=127.0.0.1",
      "--dashboard_port=" + std::to_string(emulator_->dashboard_port()),
      "--primary_port=" + std::to_string(emulator_->primary_port()),
      "--rtde_port=" + std::to_string(emulator_->rtde_port()),
      "--status_listen=127.0.0.1:0",
  };
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    const int fd = ::open(log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd >= 0) {
      ::dup2(fd, 1);
      ::dup2(fd, 2);
    }
    std::vector<char*> argv;
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  const bool running = WaitForProgramRunning(absl::Seconds(90));
  if (!running) ::kill(pid, SIGKILL);
  ASSERT_TRUE(running);
  const absl::Time signalled = absl::Now();
  ASSERT_EQ(::kill(pid, SIGTERM), 0);
  int wstatus = 0;
  pid_t done = 0;
  while (done == 0 && absl::Now() - signalled < absl::Seconds(20)) {
    done = ::waitpid(pid, &wstatus, WNOHANG);
    if (done == 0) std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  if (done == 0) {
    ::kill(pid, SIGKILL);
    ::waitpid(pid, &wstatus, 0);
  }
  std::ifstream in(log_path);
  std::stringstream log;
  log << in.rdbuf();
  ASSERT_EQ(done, pid) << "still running 20 s after SIGTERM\n" << log.str();
  EXPECT_LT(absl::Now() - signalled, absl::Seconds(10)) << log.str();
  ASSERT_TRUE(WIFEXITED(wstatus)) << log.str();
  EXPECT_EQ(WEXITSTATUS(wstatus), 0) << log.str();
  // The program was stopped by the daemon, not left running, and nothing
  // else was sent.
  EXPECT_FALSE(emulator_->Snapshot().program_running);
  const std::vector<ur_emulator::ExecutedProgram> programs = emulator_->Programs();
  ASSERT_FALSE(programs.empty());
  EXPECT_EQ(programs.back().outcome, ProgramOutcome::kAborted) << log.str();
  EXPECT_TRUE(NoProgramSentFor(absl::Seconds(1)));
  EXPECT_NE(log.str().find("UNKNOWN"), std::string::npos) << log.str();
}

}  // namespace
}  // namespace cornerpose::robot_client
