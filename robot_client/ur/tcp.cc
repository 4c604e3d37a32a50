#include "robot_client/ur/tcp.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <mutex>

#include "absl/strings/str_cat.h"

namespace cornerpose::ur {
namespace {

std::string ErrnoText(int err) { return std::strerror(err); }

absl::Status ErrnoStatus(absl::string_view what, int err) {
  const std::string message = absl::StrCat(what, ": ", ErrnoText(err));
  switch (err) {
    case ECONNREFUSED:
    case ECONNRESET:
    case ECONNABORTED:
    case EPIPE:
    case ENOTCONN:
    case EHOSTUNREACH:
    case ENETUNREACH:
    case ESHUTDOWN:
    case EBADF:
      return absl::UnavailableError(message);
    case ETIMEDOUT:
      return absl::DeadlineExceededError(message);
    default:
      return absl::InternalError(message);
  }
}

// Milliseconds for poll() until `deadline`; -1 for an infinite one.
int PollTimeoutMs(absl::Time deadline) {
  if (deadline == absl::InfiniteFuture()) return -1;
  const absl::Duration left = deadline - absl::Now();
  if (left <= absl::ZeroDuration()) return 0;
  const int64_t ms = absl::ToInt64Milliseconds(absl::Ceil(left, absl::Milliseconds(1)));
  return static_cast<int>(std::min<int64_t>(ms, 1 << 30));
}

absl::Time DeadlineFrom(absl::Duration timeout) {
  if (timeout == absl::InfiniteDuration()) return absl::InfiniteFuture();
  return absl::Now() + timeout;
}

// Polls fd for `events` until the deadline. OK when ready (or hung up, so
// the next call reports it); DEADLINE_EXCEEDED on timeout.
absl::Status WaitFor(int fd, short events, absl::Time deadline, absl::string_view what) {
  while (true) {
    pollfd p{fd, events, 0};
    const int n = ::poll(&p, 1, PollTimeoutMs(deadline));
    if (n > 0) return absl::OkStatus();
    if (n == 0) {
      if (absl::Now() >= deadline)
        return absl::DeadlineExceededError(absl::StrCat(what, ": timed out"));
      continue;
    }
    if (errno == EINTR) continue;
    return ErrnoStatus(what, errno);
  }
}

std::string AddressText(const sockaddr_storage& addr) {
  char host[INET6_ADDRSTRLEN] = {};
  int port = 0;
  if (addr.ss_family == AF_INET) {
    const auto* a = reinterpret_cast<const sockaddr_in*>(&addr);
    ::inet_ntop(AF_INET, &a->sin_addr, host, sizeof(host));
    port = ntohs(a->sin_port);
  } else if (addr.ss_family == AF_INET6) {
    const auto* a = reinterpret_cast<const sockaddr_in6*>(&addr);
    ::inet_ntop(AF_INET6, &a->sin6_addr, host, sizeof(host));
    port = ntohs(a->sin6_port);
  }
  return absl::StrCat(host, ":", port);
}

struct AddrInfoDeleter {
  void operator()(addrinfo* a) const { ::freeaddrinfo(a); }
};

absl::StatusOr<std::unique_ptr<addrinfo, AddrInfoDeleter>> Resolve(absl::string_view host, int port,
                                                                   bool passive) {
  if (port < 0 || port > 65535) {
    return absl::InvalidArgumentError(absl::StrCat("port ", port, " out of range"));
  }
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  hints.ai_flags = AI_NUMERICSERV | (passive ? AI_PASSIVE : 0);
  addrinfo* result = nullptr;
  const std::string host_string(host);
  const std::string port_string = absl::StrCat(port);
  const int rc = ::getaddrinfo(host_string.empty() ? nullptr : host_string.c_str(),
                               port_string.c_str(), &hints, &result);
  if (rc != 0) {
    return absl::InvalidArgumentError(
        absl::StrCat("cannot resolve '", host, "': ", ::gai_strerror(rc)));
  }
  return std::unique_ptr<addrinfo, AddrInfoDeleter>(result);
}

}  // namespace

// ---- TcpConnection ----

struct TcpConnection::Impl {
  int fd = -1;
  std::atomic<bool> shut_down{false};
  std::mutex write_mutex;
  std::string pending;  // read past a line end; reader thread only
  std::string peer;

  ~Impl() {
    if (fd >= 0) ::close(fd);
  }
};

TcpConnection::TcpConnection() = default;
TcpConnection::TcpConnection(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
TcpConnection::~TcpConnection() = default;
TcpConnection::TcpConnection(TcpConnection&&) noexcept = default;
TcpConnection& TcpConnection::operator=(TcpConnection&&) noexcept = default;

TcpConnection TcpConnection::FromFd(int fd) {
  auto impl = std::make_unique<Impl>();
  impl->fd = fd;
  const int one = 1;
  ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof(one));
  sockaddr_storage addr{};
  socklen_t len = sizeof(addr);
  if (::getpeername(fd, reinterpret_cast<sockaddr*>(&addr), &len) == 0) {
    impl->peer = AddressText(addr);
  }
  return TcpConnection(std::move(impl));
}

absl::StatusOr<TcpConnection> TcpConnection::Connect(absl::string_view host, int port,
                                                     absl::Duration timeout) {
  absl::StatusOr<std::unique_ptr<addrinfo, AddrInfoDeleter>> addresses =
      Resolve(host, port, /*passive=*/false);
  if (!addresses.ok()) return addresses.status();
  const absl::Time deadline = DeadlineFrom(timeout);
  const std::string where = absl::StrCat("connect to ", host, ":", port);
  absl::Status last = absl::UnavailableError(absl::StrCat(where, ": no address"));
  for (addrinfo* a = addresses->get(); a != nullptr; a = a->ai_next) {
    const int fd =
        ::socket(a->ai_family, a->ai_socktype | SOCK_CLOEXEC | SOCK_NONBLOCK, a->ai_protocol);
    if (fd < 0) {
      last = ErrnoStatus(where, errno);
      continue;
    }
    int rc = ::connect(fd, a->ai_addr, a->ai_addrlen);
    if (rc != 0 && errno == EINPROGRESS) {
      absl::Status waited = WaitFor(fd, POLLOUT, deadline, where);
      if (!waited.ok()) {
        ::close(fd);
        return waited;
      }
      int err = 0;
      socklen_t len = sizeof(err);
      ::getsockopt(fd, SOL_SOCKET, SO_ERROR, &err, &len);
      if (err != 0) {
        errno = err;
        rc = -1;
      } else {
        rc = 0;
      }
    }
    if (rc != 0) {
      last = ErrnoStatus(where, errno);
      ::close(fd);
      continue;
    }
    // Keep-alive: a peer that vanished without a FIN or RST (power cut,
    // cable pulled) is found in about 4 s even when nothing is written.
    // The clients' read timeouts catch a peer that is there but silent.
    const int one = 1, idle_s = 1, interval_s = 1, probes = 3;
    ::setsockopt(fd, SOL_SOCKET, SO_KEEPALIVE, &one, sizeof(one));
    ::setsockopt(fd, IPPROTO_TCP, TCP_KEEPIDLE, &idle_s, sizeof(idle_s));
    ::setsockopt(fd, IPPROTO_TCP, TCP_KEEPINTVL, &interval_s, sizeof(interval_s));
    ::setsockopt(fd, IPPROTO_TCP, TCP_KEEPCNT, &probes, sizeof(probes));
    return FromFd(fd);
  }
  return last;
}

bool TcpConnection::valid() const { return impl_ != nullptr && impl_->fd >= 0; }

absl::Status TcpConnection::WriteAll(absl::string_view data, absl::Duration timeout) {
  if (!valid()) return absl::UnavailableError("write: not connected");
  std::lock_guard<std::mutex> lock(impl_->write_mutex);
  const absl::Time deadline = DeadlineFrom(timeout);
  while (!data.empty()) {
    if (impl_->shut_down) return absl::UnavailableError("write: connection shut down");
    const ssize_t n = ::send(impl_->fd, data.data(), data.size(), MSG_NOSIGNAL | MSG_DONTWAIT);
    if (n > 0) {
      data.remove_prefix(static_cast<size_t>(n));
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) {
      if (absl::Status s = WaitFor(impl_->fd, POLLOUT, deadline, "write"); !s.ok()) return s;
      continue;
    }
    return ErrnoStatus(absl::StrCat("write to ", impl_->peer), n < 0 ? errno : EPIPE);
  }
  return absl::OkStatus();
}

absl::StatusOr<std::string> TcpConnection::Read(size_t max_bytes, absl::Duration timeout) {
  if (!valid()) return absl::UnavailableError("read: not connected");
  if (max_bytes == 0) return std::string();
  if (!impl_->pending.empty()) {
    const size_t n = std::min(max_bytes, impl_->pending.size());
    std::string out = impl_->pending.substr(0, n);
    impl_->pending.erase(0, n);
    return out;
  }
  const absl::Time deadline = DeadlineFrom(timeout);
  std::string buffer(std::min<size_t>(max_bytes, 1 << 16), '\0');
  while (true) {
    if (impl_->shut_down) return absl::UnavailableError("read: connection shut down");
    const ssize_t n = ::recv(impl_->fd, buffer.data(), buffer.size(), MSG_DONTWAIT);
    if (n > 0) {
      buffer.resize(static_cast<size_t>(n));
      return buffer;
    }
    if (n == 0) {
      return absl::UnavailableError(absl::StrCat("connection closed by ", impl_->peer));
    }
    if (errno == EINTR) continue;
    if (errno == EAGAIN || errno == EWOULDBLOCK) {
      if (absl::Status s = WaitFor(impl_->fd, POLLIN, deadline, "read"); !s.ok()) return s;
      continue;
    }
    return ErrnoStatus(absl::StrCat("read from ", impl_->peer), errno);
  }
}

absl::StatusOr<std::string> TcpConnection::ReadExact(size_t n, absl::Duration timeout) {
  const absl::Time deadline = DeadlineFrom(timeout);
  std::string out;
  out.reserve(n);
  while (out.size() < n) {
    const absl::Duration left =
        deadline == absl::InfiniteFuture() ? absl::InfiniteDuration() : deadline - absl::Now();
    absl::StatusOr<std::string> chunk = Read(n - out.size(), std::max(left, absl::ZeroDuration()));
    if (!chunk.ok()) {
      // Keep what arrived, so a retry after a timeout does not lose bytes.
      if (valid()) impl_->pending.insert(0, out);
      return chunk.status();
    }
    out += *chunk;
  }
  return out;
}

absl::StatusOr<std::string> TcpConnection::ReadLine(absl::Duration timeout, size_t max_length) {
  if (!valid()) return absl::UnavailableError("read: not connected");
  const absl::Time deadline = DeadlineFrom(timeout);
  std::string line;
  while (true) {
    const size_t newline = line.find('\n');
    if (newline != std::string::npos) {
      impl_->pending.insert(0, line.substr(newline + 1));
      line.resize(newline);
      if (!line.empty() && line.back() == '\r') line.pop_back();
      return line;
    }
    if (line.size() > max_length) {
      impl_->pending.insert(0, line);
      return absl::ResourceExhaustedError(
          absl::StrCat("line from ", impl_->peer, " longer than ", max_length, " bytes"));
    }
    const absl::Duration left =
        deadline == absl::InfiniteFuture() ? absl::InfiniteDuration() : deadline - absl::Now();
    absl::StatusOr<std::string> chunk = Read(4096, std::max(left, absl::ZeroDuration()));
    if (!chunk.ok()) {
      impl_->pending.insert(0, line);
      return chunk.status();
    }
    line += *chunk;
  }
}

void TcpConnection::Shutdown() {
  if (impl_ == nullptr || impl_->fd < 0) return;
  impl_->shut_down = true;
  ::shutdown(impl_->fd, SHUT_RDWR);
}

void TcpConnection::Close() {
  if (impl_ == nullptr) return;
  Shutdown();
  impl_.reset();
}

std::string TcpConnection::peer() const { return impl_ == nullptr ? "" : impl_->peer; }

// ---- TcpListener ----

struct TcpListener::Impl {
  int fd = -1;
  int wake[2] = {-1, -1};  // self-pipe: Close() writes, Accept() polls it
  int port = 0;
  std::atomic<bool> closed{false};

  ~Impl() {
    if (fd >= 0) ::close(fd);
    for (int w : wake) {
      if (w >= 0) ::close(w);
    }
  }
};

TcpListener::TcpListener() = default;
TcpListener::~TcpListener() { Close(); }
TcpListener::TcpListener(TcpListener&&) noexcept = default;
TcpListener& TcpListener::operator=(TcpListener&& other) noexcept {
  if (this != &other) {
    Close();
    impl_ = std::move(other.impl_);
  }
  return *this;
}

absl::StatusOr<TcpListener> TcpListener::Listen(absl::string_view host, int port, int backlog) {
  absl::StatusOr<std::unique_ptr<addrinfo, AddrInfoDeleter>> addresses =
      Resolve(host, port, /*passive=*/true);
  if (!addresses.ok()) return addresses.status();
  const std::string where = absl::StrCat("listen on ", host, ":", port);
  absl::Status last = absl::UnavailableError(absl::StrCat(where, ": no address"));
  for (addrinfo* a = addresses->get(); a != nullptr; a = a->ai_next) {
    auto impl = std::make_unique<Impl>();
    impl->fd =
        ::socket(a->ai_family, a->ai_socktype | SOCK_CLOEXEC | SOCK_NONBLOCK, a->ai_protocol);
    if (impl->fd < 0) {
      last = ErrnoStatus(where, errno);
      continue;
    }
    const int one = 1;
    ::setsockopt(impl->fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof(one));
    if (::bind(impl->fd, a->ai_addr, a->ai_addrlen) != 0 || ::listen(impl->fd, backlog) != 0) {
      last = ErrnoStatus(where, errno);
      continue;
    }
    if (::pipe2(impl->wake, O_CLOEXEC | O_NONBLOCK) != 0) return ErrnoStatus("pipe", errno);
    sockaddr_storage addr{};
    socklen_t len = sizeof(addr);
    ::getsockname(impl->fd, reinterpret_cast<sockaddr*>(&addr), &len);
    impl->port = addr.ss_family == AF_INET6
                     ? ntohs(reinterpret_cast<sockaddr_in6*>(&addr)->sin6_port)
                     : ntohs(reinterpret_cast<sockaddr_in*>(&addr)->sin_port);
    TcpListener listener;
    listener.impl_ = std::move(impl);
    return listener;
  }
  return last;
}

int TcpListener::port() const { return impl_ == nullptr ? 0 : impl_->port; }

absl::StatusOr<TcpConnection> TcpListener::Accept(absl::Duration timeout) {
  if (impl_ == nullptr) return absl::UnavailableError("accept: not listening");
  const absl::Time deadline = DeadlineFrom(timeout);
  while (true) {
    if (impl_->closed) return absl::UnavailableError("accept: listener closed");
    pollfd p[2] = {{impl_->fd, POLLIN, 0}, {impl_->wake[0], POLLIN, 0}};
    const int n = ::poll(p, 2, PollTimeoutMs(deadline));
    if (n < 0) {
      if (errno == EINTR) continue;
      return ErrnoStatus("accept", errno);
    }
    if (impl_->closed) return absl::UnavailableError("accept: listener closed");
    if (n == 0) {
      if (absl::Now() >= deadline) return absl::DeadlineExceededError("accept: timed out");
      continue;
    }
    const int fd = ::accept4(impl_->fd, nullptr, nullptr, SOCK_CLOEXEC);
    if (fd >= 0) return TcpConnection::FromFd(fd);
    if (errno == EINTR || errno == EAGAIN || errno == EWOULDBLOCK || errno == ECONNABORTED) {
      continue;
    }
    return ErrnoStatus("accept", errno);
  }
}

void TcpListener::Close() {
  if (impl_ == nullptr || impl_->closed.exchange(true)) return;
  const char byte = 1;
  while (::write(impl_->wake[1], &byte, 1) < 0 && errno == EINTR) {
  }
  // Stops accepting new connections now; the descriptor is released with
  // the object, so a concurrent Accept never polls a reused number.
  ::shutdown(impl_->fd, SHUT_RDWR);
}

}  // namespace cornerpose::ur
