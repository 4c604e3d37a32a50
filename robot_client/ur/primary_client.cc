#include "robot_client/ur/primary_client.h"

#include <algorithm>

#include "absl/strings/str_cat.h"
#include "robot_client/ur/dashboard.h"

namespace cornerpose::ur {
namespace {

constexpr absl::string_view kStarted = "PROGRAM_XXX_STARTED";
constexpr absl::string_view kStopped = "PROGRAM_XXX_STOPPED";
constexpr int32_t kReportLevelFault = 4;

// A field present in `update` replaces the one in `latest`.
void Merge(RobotState& latest, RobotState update) {
  if (update.robot_mode) latest.robot_mode = std::move(update.robot_mode);
  if (update.joints) latest.joints = std::move(update.joints);
  if (update.cartesian) latest.cartesian = std::move(update.cartesian);
  if (update.masterboard) latest.masterboard = std::move(update.masterboard);
  if (!update.other.empty()) latest.other = std::move(update.other);
  latest.order = std::move(update.order);
}

std::string SafetyText(uint8_t mode) {
  const std::optional<SafetyMode> m = SafetyModeFromInt(mode);
  return m ? SafetyModeName(*m) : absl::StrCat("safety mode ", mode);
}

}  // namespace

const char* ProgramOutcomeName(ProgramOutcome::Kind kind) {
  switch (kind) {
    case ProgramOutcome::kCompleted:
      return "completed";
    case ProgramOutcome::kRuntimeException:
      return "runtime exception";
    case ProgramOutcome::kProtectiveStop:
      return "protective stop";
    case ProgramOutcome::kConnectionLost:
      return "connection lost";
    case ProgramOutcome::kTimeout:
      return "timeout";
    case ProgramOutcome::kUnfinished:
      return "stopped without its done message";
    case ProgramOutcome::kCancelled:
      return "cancelled";
  }
  return "unknown";
}

PrimaryClient::PrimaryClient(PrimaryClientOptions options) : options_(options) {}

PrimaryClient::~PrimaryClient() { Stop(); }

void PrimaryClient::Stop() {
  if (connection_ != nullptr) connection_->Shutdown();
  if (reader_.joinable()) reader_.join();
  // A SendScript in flight fails fast on the shut-down socket; wait for it
  // before the connection goes away.
  std::lock_guard<std::mutex> send_lock(send_mutex_);
  std::lock_guard<std::mutex> lock(mutex_);
  connection_.reset();
  connected_ = false;
  changed_.notify_all();
}

void PrimaryClient::Close() {
  Stop();
  std::lock_guard<std::mutex> lock(mutex_);
  connection_status_ = absl::UnavailableError("primary client closed");
}

absl::Status PrimaryClient::Connect(absl::string_view host, int port, absl::Duration timeout) {
  Stop();
  absl::StatusOr<TcpConnection> connection = TcpConnection::Connect(host, port, timeout);
  if (!connection.ok()) return connection.status();
  {
    std::lock_guard<std::mutex> lock(mutex_);
    connection_ = std::make_unique<TcpConnection>(std::move(*connection));
    connected_ = true;
    connection_status_ = absl::OkStatus();
    latest_.reset();
    version_.reset();
    messages_.clear();
  }
  reader_ = std::thread([this, c = connection_.get()] { ReadLoop(c); });
  return absl::OkStatus();
}

bool PrimaryClient::connected() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return connected_;
}

absl::Status PrimaryClient::connection_status() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return connection_status_;
}

void PrimaryClient::ReadLoop(TcpConnection* connection) {
  PrimaryFramer framer;
  absl::Status status;
  while (status.ok()) {
    absl::StatusOr<std::string> bytes = connection->Read(1 << 16, options_.read_timeout);
    if (!bytes.ok()) {
      status = bytes.status();
      if (absl::IsDeadlineExceeded(status)) {
        // Open but silent: a half-open link or a hung controller.
        status = absl::UnavailableError(
            absl::StrCat("primary interface silent for ", absl::FormatDuration(options_.read_timeout),
                         " (link half-open or controller hung)"));
      }
      break;
    }
    framer.Append(*bytes);
    while (true) {
      absl::StatusOr<std::optional<std::string>> frame = framer.Next();
      if (!frame.ok()) {
        status = frame.status();
        break;
      }
      if (!frame->has_value()) break;
      absl::StatusOr<PrimaryPackage> package = ParsePrimaryPackage(**frame);
      // A package this parser cannot decode is skipped: the framing is
      // intact, and the next one may be fine.
      if (!package.ok()) continue;
      std::lock_guard<std::mutex> lock(mutex_);
      if (RobotState* state = std::get_if<RobotState>(&*package)) {
        if (!latest_) latest_.emplace();
        Merge(*latest_, std::move(*state));
        ++state_count_;
      } else if (std::holds_alternative<OtherPackage>(*package)) {
        continue;
      } else {
        if (const auto* v = std::get_if<VersionMessage>(&*package)) version_ = *v;
        messages_.push_back(std::move(*package));
        if (messages_.size() > kMaxQueuedMessages) messages_.pop_front();
      }
      changed_.notify_all();
    }
  }
  connection->Shutdown();
  std::lock_guard<std::mutex> lock(mutex_);
  connected_ = false;
  connection_status_ = status;
  changed_.notify_all();
}

absl::Status PrimaryClient::SendScript(absl::string_view script) {
  std::lock_guard<std::mutex> send_lock(send_mutex_);
  TcpConnection* connection = nullptr;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!connected_ || connection_ == nullptr) {
      return absl::UnavailableError(
          absl::StrCat("primary: not connected: ", connection_status_.message()));
    }
    connection = connection_.get();
    messages_.clear();
    state_count_at_send_ = state_count_;
  }
  std::string text(script);
  if (text.empty() || text.back() != '\n') text.push_back('\n');
  return connection->WriteAll(text);
}

ProgramOutcome PrimaryClient::WaitForProgram(absl::string_view name, absl::Duration timeout) {
  ProgramWait wait;
  wait.timeout = timeout;
  return WaitForProgram(name, wait);
}

ProgramOutcome PrimaryClient::WaitForProgram(absl::string_view name, const ProgramWait& wait) {
  const absl::Duration timeout = wait.timeout;
  const absl::Time deadline = absl::Now() + timeout;
  bool done_seen = false;
  ProgramOutcome outcome;
  std::unique_lock<std::mutex> lock(mutex_);
  // Only states received after the script was sent: one from before may
  // still show a stop that has been cleared since.
  const uint64_t first_state = state_count_at_send_;
  uint64_t checked_state = first_state;
  while (true) {
    while (!messages_.empty()) {
      PrimaryPackage package = std::move(messages_.front());
      messages_.pop_front();
      if (const auto* key = std::get_if<KeyMessage>(&package)) {
        if (key->text != name) continue;
        if (key->title == kStarted) outcome.started = true;
        if (key->title == kStopped) {
          if (wait.done_text.empty() || done_seen) {
            outcome.kind = ProgramOutcome::kCompleted;
            outcome.detail = absl::StrCat("program ", name, " stopped");
          } else {
            outcome.kind = ProgramOutcome::kUnfinished;
            outcome.detail = absl::StrCat("program ", name, " stopped without its done message '",
                                          wait.done_text, "'");
          }
          return outcome;
        }
      } else if (const auto* text = std::get_if<TextMessage>(&package)) {
        outcome.text_messages.push_back(text->text);
        if (!wait.done_text.empty() && text->text == wait.done_text) done_seen = true;
      } else if (const auto* e = std::get_if<RuntimeExceptionMessage>(&package)) {
        outcome.kind = ProgramOutcome::kRuntimeException;
        outcome.detail = absl::StrCat("line ", e->line, ", column ", e->column, ": ", e->text);
        return outcome;
      } else if (const auto* s = std::get_if<SafetyModeMessage>(&package)) {
        const auto mode = static_cast<SafetyMode>(s->safety_mode);
        if (mode != SafetyMode::kNormal && mode != SafetyMode::kReduced) {
          outcome.kind = ProgramOutcome::kProtectiveStop;
          outcome.detail = absl::StrCat("safety mode ", SafetyText(s->safety_mode));
          return outcome;
        }
      } else if (const auto* c = std::get_if<ErrorCodeMessage>(&package)) {
        if (c->report_level >= kReportLevelFault) {
          outcome.kind = ProgramOutcome::kRuntimeException;
          outcome.detail = absl::StrCat("error C", c->code, "A", c->argument, ": ", c->text);
          return outcome;
        }
      }
    }
    if (state_count_ != checked_state) {
      checked_state = state_count_;
      if (state_count_ > first_state && latest_ && latest_->robot_mode) {
        const RobotModeData& m = *latest_->robot_mode;
        if (m.protective_stopped || m.emergency_stopped) {
          outcome.kind = ProgramOutcome::kProtectiveStop;
          outcome.detail = m.protective_stopped ? "robot mode data: protective stopped"
                                                : "robot mode data: emergency stopped";
          return outcome;
        }
      }
    }
    if (!connected_) {
      outcome.kind = ProgramOutcome::kConnectionLost;
      outcome.detail = std::string(connection_status_.message());
      return outcome;
    }
    if (absl::Now() >= deadline) {
      outcome.kind = ProgramOutcome::kTimeout;
      outcome.detail =
          absl::StrCat("program ", name, outcome.started ? " still running" : " did not start",
                       " after ", absl::FormatDuration(timeout));
      return outcome;
    }
    if (wait.cancel) {
      // The check may take other locks (the RTDE client's): not under ours.
      lock.unlock();
      std::optional<std::string> reason = wait.cancel();
      lock.lock();
      if (reason) {
        outcome.kind = ProgramOutcome::kCancelled;
        outcome.detail = *std::move(reason);
        return outcome;
      }
      if (!messages_.empty() || state_count_ != checked_state || !connected_) continue;
      changed_.wait_until(lock, absl::ToChronoTime(std::min(deadline, absl::Now() + wait.cancel_poll)));
    } else {
      changed_.wait_until(lock, absl::ToChronoTime(deadline));
    }
  }
}

std::optional<RobotState> PrimaryClient::LatestState() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return latest_;
}

uint64_t PrimaryClient::state_count() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return state_count_;
}

bool PrimaryClient::WaitForStateCount(uint64_t count, absl::Duration timeout) const {
  std::unique_lock<std::mutex> lock(mutex_);
  return changed_.wait_until(lock, absl::ToChronoTime(absl::Now() + timeout), [&] {
    return state_count_ > count || !connected_;
  }) && state_count_ > count;
}

std::optional<VersionMessage> PrimaryClient::version() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return version_;
}

std::vector<PrimaryPackage> PrimaryClient::TakeMessages() {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<PrimaryPackage> out(std::make_move_iterator(messages_.begin()),
                                  std::make_move_iterator(messages_.end()));
  messages_.clear();
  return out;
}

}  // namespace cornerpose::ur
