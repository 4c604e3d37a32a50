#include "tests/support/ur_emulator/servers.h"

#include <algorithm>
#include <chrono>
#include <thread>

#include "absl/strings/str_cat.h"
#include "robot_client/ur/dashboard.h"
#include "robot_client/ur/rtde.h"
#include "tests/support/ur_emulator/sessions.h"

namespace cornerpose::ur_emulator {
namespace {

// How often blocked reads look at the stop flag.
constexpr absl::Duration kPoll = absl::Milliseconds(100);

bool IsTimeout(const absl::Status& status) { return absl::IsDeadlineExceeded(status); }

}  // namespace

TcpServer::~TcpServer() {
  stopping_ = true;
  listener_.Close();
  if (accept_thread_.joinable()) accept_thread_.join();
  std::list<Client> clients;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    for (Client& c : clients_) c.connection->Shutdown();
    clients.swap(clients_);
  }
  for (Client& c : clients) c.thread.join();
}

absl::Status TcpServer::Start(const std::string& host, int port, Handler handler) {
  auto listener = ur::TcpListener::Listen(host, port);
  if (!listener.ok()) return listener.status();
  listener_ = std::move(*listener);
  port_ = listener_.port();
  handler_ = std::move(handler);
  accept_thread_ = std::thread([this] { AcceptLoop(); });
  return absl::OkStatus();
}

void TcpServer::ReapLocked() {
  for (auto it = clients_.begin(); it != clients_.end();) {
    if (*it->done) {
      it->thread.join();
      it = clients_.erase(it);
    } else {
      ++it;
    }
  }
}

void TcpServer::AcceptLoop() {
  while (!stopping_) {
    auto connection = listener_.Accept(kPoll);
    {
      std::lock_guard<std::mutex> lock(mutex_);
      ReapLocked();
    }
    if (!connection.ok()) {
      if (IsTimeout(connection.status())) continue;
      if (stopping_) break;
      continue;  // a failed accept (e.g. a reset peer) does not end the server
    }
    Client client;
    client.connection = std::make_shared<ur::TcpConnection>(std::move(*connection));
    client.done = std::make_shared<std::atomic<bool>>(false);
    std::lock_guard<std::mutex> lock(mutex_);
    if (stopping_) break;
    client.thread = std::thread([this, c = client.connection, done = client.done] {
      handler_(*c, stopping_);
      c->Shutdown();
      *done = true;
    });
    clients_.push_back(std::move(client));
  }
}

void TcpServer::DropConnections() {
  std::lock_guard<std::mutex> lock(mutex_);
  for (Client& c : clients_) c.connection->Shutdown();
}

absl::Status Servers::Start() {
  const UrEmulatorOptions& o = controller_.options();
  absl::Status status = dashboard_.Start(
      o.host, o.dashboard_port,
      [this](ur::TcpConnection& c, const std::atomic<bool>& s) { ServeDashboard(c, s); });
  if (!status.ok())
    return absl::Status(status.code(), absl::StrCat("dashboard: ", status.message()));
  status = primary_.Start(
      o.host, o.primary_port,
      [this](ur::TcpConnection& c, const std::atomic<bool>& s) { ServePrimary(c, s); });
  if (!status.ok()) return absl::Status(status.code(), absl::StrCat("primary: ", status.message()));
  status =
      rtde_.Start(o.host, o.rtde_port,
                  [this](ur::TcpConnection& c, const std::atomic<bool>& s) { ServeRtde(c, s); });
  if (!status.ok()) return absl::Status(status.code(), absl::StrCat("rtde: ", status.message()));
  return absl::OkStatus();
}

void Servers::DropConnections() {
  dashboard_.DropConnections();
  primary_.DropConnections();
  rtde_.DropConnections();
}

void Servers::ServeDashboard(ur::TcpConnection& connection, const std::atomic<bool>& stopping) {
  if (!connection.WriteAll(absl::StrCat(ur::kDashboardBanner, "\n")).ok()) return;
  while (!stopping) {
    if (silent_) {
      std::this_thread::sleep_for(absl::ToChronoMilliseconds(kPoll));
      continue;
    }
    auto line = connection.ReadLine(kPoll);
    if (!line.ok()) {
      if (IsTimeout(line.status())) continue;
      return;
    }
    bool close = false;
    const std::string reply = DashboardReply(controller_, *line, &close);
    if (!connection.WriteAll(absl::StrCat(reply, "\n")).ok() || close) return;
  }
}

void Servers::ServePrimary(ur::TcpConnection& connection, const std::atomic<bool>& stopping) {
  // A writer thread streams state and events; this thread reads scripts.
  uint64_t cursor = controller_.EventCursor();
  std::atomic<bool> done{false};
  std::thread writer([&] {
    const auto period = std::chrono::duration_cast<std::chrono::steady_clock::duration>(
        std::chrono::duration<double>(1.0 / controller_.options().primary_state_hz));
    auto next_state = std::chrono::steady_clock::now();
    bool ok = connection.WriteAll(EncodePrimaryVersion(controller_.options())).ok();
    while (ok && !done && !stopping) {
      if (silent_) {
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
        continue;
      }
      auto now = std::chrono::steady_clock::now();
      if (now >= next_state) {
        ok = connection.WriteAll(EncodePrimaryState(controller_.Snapshot())).ok();
        next_state = std::max(next_state + period, now);
        continue;
      }
      const auto wait = std::min<std::chrono::steady_clock::duration>(
          next_state - now, std::chrono::milliseconds(100));
      for (const ControllerEvent& event : controller_.NextEvents(&cursor, absl::FromChrono(wait))) {
        if (!ok) break;
        ok = connection.WriteAll(EncodePrimaryEvent(event)).ok();
      }
    }
    connection.Shutdown();
  });
  PrimaryScriptAssembler assembler;
  while (!stopping) {
    auto line = connection.ReadLine(kPoll);
    if (!line.ok()) {
      if (IsTimeout(line.status())) continue;
      break;
    }
    auto item = assembler.AddLine(*line);
    if (!item) continue;
    if (item->control_word) {
      ApplyPrimaryControlWord(controller_, item->text);
    } else {
      controller_.SubmitScript(item->text);
    }
  }
  done = true;
  connection.Shutdown();
  writer.join();
}

void Servers::ServeRtde(ur::TcpConnection& connection, const std::atomic<bool>& stopping) {
  RtdeSession session(controller_.options());
  ur::RtdeFramer framer;
  auto next_package = std::chrono::steady_clock::now();
  while (!stopping) {
    if (silent_) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
      continue;
    }
    absl::Duration timeout = kPoll;
    if (session.streaming() && !rtde_stalled_) {
      const auto now = std::chrono::steady_clock::now();
      if (now >= next_package) {
        if (!connection.WriteAll(session.DataPackage(controller_.Snapshot())).ok()) return;
        const auto period = std::chrono::duration_cast<std::chrono::steady_clock::duration>(
            std::chrono::duration<double>(session.period_s()));
        // Late (a slow machine): go on from now instead of bursting.
        next_package = std::max(next_package + period, now);
        continue;
      }
      timeout = std::max(absl::FromChrono(next_package - now), absl::Microseconds(100));
    }
    auto bytes = connection.Read(4096, timeout);
    if (!bytes.ok()) {
      if (IsTimeout(bytes.status())) continue;
      return;
    }
    framer.Append(*bytes);
    while (true) {
      auto frame = framer.Next();
      if (!frame.ok()) return;  // the stream cannot be resynchronised
      if (!frame->has_value()) break;
      const bool was_streaming = session.streaming();
      const std::string reply = session.Handle(**frame);
      if (!reply.empty() && !connection.WriteAll(reply).ok()) return;
      if (!was_streaming && session.streaming()) next_package = std::chrono::steady_clock::now();
    }
  }
}

}  // namespace cornerpose::ur_emulator
