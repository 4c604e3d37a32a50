// Small blocking POSIX TCP helpers with timeouts, shared by the UR clients
// and the controller emulator. Every wait is a poll() with a timeout; errors
// are absl::Status: UNAVAILABLE for refused / closed / shut-down sockets,
// DEADLINE_EXCEEDED for timeouts, INVALID_ARGUMENT for bad addresses.
// SIGPIPE is never raised (MSG_NOSIGNAL).
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "absl/time/time.h"

namespace cornerpose::ur {

// One connected socket. Move-only; closes on destruction. One thread may
// read while another writes; Shutdown() may be called from any thread and
// makes blocked and later reads and writes fail with UNAVAILABLE.
class TcpConnection {
 public:
  TcpConnection();
  ~TcpConnection();
  TcpConnection(TcpConnection&&) noexcept;
  TcpConnection& operator=(TcpConnection&&) noexcept;

  // host: a name or numeric IPv4/IPv6 address.
  static absl::StatusOr<TcpConnection> Connect(absl::string_view host, int port,
                                               absl::Duration timeout);
  // Takes ownership of a connected socket.
  static TcpConnection FromFd(int fd);

  bool valid() const;

  // Writes all of `data` (serialised between writers).
  absl::Status WriteAll(absl::string_view data, absl::Duration timeout = absl::Seconds(10));
  // At least one and at most max_bytes bytes.
  absl::StatusOr<std::string> Read(size_t max_bytes, absl::Duration timeout);
  // Exactly n bytes within `timeout` in total.
  absl::StatusOr<std::string> ReadExact(size_t n, absl::Duration timeout);
  // One line without its "\n" (and without a trailing "\r"). Bytes after the
  // newline are kept for the next read. RESOURCE_EXHAUSTED past max_length.
  absl::StatusOr<std::string> ReadLine(absl::Duration timeout, size_t max_length = 65536);

  // Shuts both directions down: wakes a blocked reader. Thread-safe.
  void Shutdown();
  // Shutdown and close now (not thread-safe against concurrent use).
  void Close();

  // "address:port" of the peer, for messages.
  std::string peer() const;

 private:
  struct Impl;
  explicit TcpConnection(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

// A listening socket. Close() (from any thread) wakes a blocked Accept.
class TcpListener {
 public:
  TcpListener();
  ~TcpListener();
  TcpListener(TcpListener&&) noexcept;
  TcpListener& operator=(TcpListener&&) noexcept;

  // port 0: the OS picks a free port (see port()).
  static absl::StatusOr<TcpListener> Listen(absl::string_view host, int port, int backlog = 16);

  int port() const;
  // UNAVAILABLE once closed; DEADLINE_EXCEEDED when nobody connects in time.
  absl::StatusOr<TcpConnection> Accept(absl::Duration timeout);
  // Stops listening and wakes Accept. Thread-safe, idempotent.
  void Close();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace cornerpose::ur
