#include "robot_client/ur/tcp.h"

#include <gtest/gtest.h>

#include <thread>

namespace cornerpose::ur {
namespace {

constexpr absl::Duration kLong = absl::Seconds(30);  // never reached when all is well

struct Pair {
  TcpListener listener;
  TcpConnection client;
  TcpConnection server;
};

Pair Connected() {
  Pair p;
  absl::StatusOr<TcpListener> listener = TcpListener::Listen("127.0.0.1", 0);
  EXPECT_TRUE(listener.ok()) << listener.status();
  p.listener = std::move(*listener);
  EXPECT_GT(p.listener.port(), 0);
  absl::StatusOr<TcpConnection> client =
      TcpConnection::Connect("127.0.0.1", p.listener.port(), kLong);
  EXPECT_TRUE(client.ok()) << client.status();
  absl::StatusOr<TcpConnection> server = p.listener.Accept(kLong);
  EXPECT_TRUE(server.ok()) << server.status();
  p.client = std::move(*client);
  p.server = std::move(*server);
  return p;
}

TEST(Tcp, WriteReadExactAndLines) {
  Pair p = Connected();
  ASSERT_TRUE(p.client.WriteAll("Connected: hello\r\nsecond\nthird-part").ok());
  absl::StatusOr<std::string> line = p.server.ReadLine(kLong);
  ASSERT_TRUE(line.ok()) << line.status();
  EXPECT_EQ(*line, "Connected: hello");
  EXPECT_EQ(*p.server.ReadLine(kLong), "second");
  // What follows the last newline is kept for the next read.
  EXPECT_EQ(*p.server.ReadExact(5, kLong), "third");
  ASSERT_TRUE(p.client.WriteAll("!\n").ok());
  EXPECT_EQ(*p.server.ReadLine(kLong), "-part!");

  const std::string big(300000, 'x');
  std::thread writer([&] { EXPECT_TRUE(p.server.WriteAll(big, kLong).ok()); });
  absl::StatusOr<std::string> got = p.client.ReadExact(big.size(), kLong);
  writer.join();
  ASSERT_TRUE(got.ok()) << got.status();
  EXPECT_EQ(*got, big);
  EXPECT_FALSE(p.client.peer().empty());
}

TEST(Tcp, ConnectRefusedIsUnavailable) {
  int port = 0;
  {
    absl::StatusOr<TcpListener> listener = TcpListener::Listen("127.0.0.1", 0);
    ASSERT_TRUE(listener.ok());
    port = listener->port();
  }
  const absl::StatusOr<TcpConnection> c = TcpConnection::Connect("127.0.0.1", port, kLong);
  ASSERT_FALSE(c.ok());
  EXPECT_EQ(c.status().code(), absl::StatusCode::kUnavailable) << c.status();
}

TEST(Tcp, BadAddressesAreInvalid) {
  EXPECT_EQ(TcpConnection::Connect("no.such.host.invalid", 1, absl::Seconds(5)).status().code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(TcpListener::Listen("127.0.0.1", 70000).status().code(),
            absl::StatusCode::kInvalidArgument);
}

TEST(Tcp, ReadTimeoutIsDeadlineExceeded) {
  Pair p = Connected();
  const absl::StatusOr<std::string> r = p.client.Read(10, absl::Milliseconds(20));
  EXPECT_EQ(r.status().code(), absl::StatusCode::kDeadlineExceeded);
  EXPECT_EQ(p.client.ReadLine(absl::Milliseconds(20)).status().code(),
            absl::StatusCode::kDeadlineExceeded);
  // A partial line survives the timeout.
  ASSERT_TRUE(p.server.WriteAll("abc").ok());
  EXPECT_EQ(*p.client.ReadExact(1, kLong), "a");
  EXPECT_EQ(p.client.ReadLine(absl::Milliseconds(20)).status().code(),
            absl::StatusCode::kDeadlineExceeded);
  ASSERT_TRUE(p.server.WriteAll("d\n").ok());
  EXPECT_EQ(*p.client.ReadLine(kLong), "bcd");
  EXPECT_EQ(p.client.ReadExact(4, absl::Milliseconds(20)).status().code(),
            absl::StatusCode::kDeadlineExceeded);
}

TEST(Tcp, ShutdownUnblocksAReader) {
  Pair p = Connected();
  absl::Status result;
  std::thread reader([&] { result = p.client.Read(100, kLong).status(); });
  // Whether the reader is already blocked or not, it must end UNAVAILABLE.
  p.client.Shutdown();
  reader.join();
  EXPECT_EQ(result.code(), absl::StatusCode::kUnavailable) << result;
  EXPECT_EQ(p.client.WriteAll("x").code(), absl::StatusCode::kUnavailable);
}

TEST(Tcp, PeerCloseIsUnavailable) {
  Pair p = Connected();
  ASSERT_TRUE(p.server.WriteAll("last").ok());
  p.server.Close();
  EXPECT_EQ(*p.client.ReadExact(4, kLong), "last");
  EXPECT_EQ(p.client.Read(10, kLong).status().code(), absl::StatusCode::kUnavailable);
  // Writing to a closed peer fails (no SIGPIPE) sooner or later.
  absl::Status w;
  for (int i = 0; i < 100 && w.ok(); ++i) w = p.client.WriteAll(std::string(10000, 'y'), kLong);
  EXPECT_EQ(w.code(), absl::StatusCode::kUnavailable) << w;
}

TEST(Tcp, LineTooLong) {
  Pair p = Connected();
  ASSERT_TRUE(p.server.WriteAll(std::string(200, 'z')).ok());
  EXPECT_EQ(p.client.ReadLine(kLong, 100).status().code(), absl::StatusCode::kResourceExhausted);
}

TEST(Tcp, CloseWakesAccept) {
  absl::StatusOr<TcpListener> listener = TcpListener::Listen("127.0.0.1", 0);
  ASSERT_TRUE(listener.ok());
  absl::Status result;
  std::thread acceptor([&] { result = listener->Accept(kLong).status(); });
  listener->Close();
  acceptor.join();
  EXPECT_EQ(result.code(), absl::StatusCode::kUnavailable) << result;
  EXPECT_EQ(listener->Accept(kLong).status().code(), absl::StatusCode::kUnavailable);
  EXPECT_EQ(listener->Accept(absl::ZeroDuration()).status().code(), absl::StatusCode::kUnavailable);
}

TEST(Tcp, AcceptTimeout) {
  absl::StatusOr<TcpListener> listener = TcpListener::Listen("127.0.0.1", 0);
  ASSERT_TRUE(listener.ok());
  EXPECT_EQ(listener->Accept(absl::Milliseconds(20)).status().code(),
            absl::StatusCode::kDeadlineExceeded);
}

TEST(Tcp, InvalidConnection) {
  TcpConnection none;
  EXPECT_FALSE(none.valid());
  EXPECT_EQ(none.Read(1, kLong).status().code(), absl::StatusCode::kUnavailable);
  EXPECT_EQ(none.WriteAll("x").code(), absl::StatusCode::kUnavailable);
  none.Shutdown();  // no-op
}

}  // namespace
}  // namespace cornerpose::ur
