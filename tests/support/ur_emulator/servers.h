// The emulator's TCP side: a listener with one thread per client that can
// drop every client at once, and the dashboard / primary / RTDE servers
// built on it from the byte-level sessions (sessions.h).
#pragma once

#include <atomic>
#include <functional>
#include <list>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "absl/status/status.h"
#include "robot_client/ur/tcp.h"
#include "tests/support/ur_emulator/controller.h"

namespace cornerpose::ur_emulator {

class TcpServer {
 public:
  // Runs on the client's own thread until the client leaves, the
  // connection is dropped (reads and writes then fail) or `stopping`.
  using Handler =
      std::function<void(ur::TcpConnection& connection, const std::atomic<bool>& stopping)>;

  TcpServer() = default;
  // Stops accepting, drops every client and joins all threads.
  ~TcpServer();
  TcpServer(const TcpServer&) = delete;
  TcpServer& operator=(const TcpServer&) = delete;

  // Listens on host:port (0: the OS chooses) and accepts in a thread.
  absl::Status Start(const std::string& host, int port, Handler handler);
  int port() const { return port_; }
  // Shuts every connected client's socket down; accepting goes on.
  void DropConnections();

 private:
  struct Client {
    std::shared_ptr<ur::TcpConnection> connection;
    std::shared_ptr<std::atomic<bool>> done;
    std::thread thread;
  };
  void AcceptLoop();
  void ReapLocked();

  ur::TcpListener listener_;
  Handler handler_;
  int port_ = 0;
  std::atomic<bool> stopping_{false};
  std::mutex mutex_;
  std::list<Client> clients_;  // guarded by mutex_
  std::thread accept_thread_;
};

// The three servers of one emulator.
class Servers {
 public:
  explicit Servers(Controller& controller) : controller_(controller) {}
  absl::Status Start();
  void DropConnections();
  // Faults. Silent: every connection (and every new one) stays open but
  // sends nothing and answers nothing (a half-open link, a hung
  // controller). RTDE stall: RTDE data packages stop; the rest goes on.
  void SetSilent(bool silent) { silent_ = silent; }
  void SetRtdeStalled(bool stalled) { rtde_stalled_ = stalled; }

  int dashboard_port() const { return dashboard_.port(); }
  int primary_port() const { return primary_.port(); }
  int rtde_port() const { return rtde_.port(); }

 private:
  void ServeDashboard(ur::TcpConnection& connection, const std::atomic<bool>& stopping);
  void ServePrimary(ur::TcpConnection& connection, const std::atomic<bool>& stopping);
  void ServeRtde(ur::TcpConnection& connection, const std::atomic<bool>& stopping);

  Controller& controller_;
  std::atomic<bool> silent_{false};
  std::atomic<bool> rtde_stalled_{false};
  TcpServer dashboard_;
  TcpServer primary_;
  TcpServer rtde_;
};

}  // namespace cornerpose::ur_emulator
