// TLS and mutual TLS on the real servers (the perception service and the
// daemon's status service) and in the clients (a channel as the benchmarks
// make it, and `cornerpose client health`), with certificates made at test
// time by scripts/make-certs (openssl): a valid client certificate works;
// none, or one from another CA, is refused; plaintext to a TLS port fails
// cleanly and the server keeps serving. Also: reflection off means off.
#include <grpcpp/create_channel.h>
#include <grpcpp/impl/codegen/client_callback.h>
#include <grpcpp/support/byte_buffer.h>
#include <grpcpp/support/sync_stream.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "common/grpc_security/tls.h"
#include "cornerpose/v1/perception_service.grpc.pb.h"
#include "grpc/health/v1/health.grpc.pb.h"
#include "robot_client/cell/cell_controller.h"
#include "robot_client/cell/perception_subscriber.h"
#include "robot_client/cell/status_service.h"
#include "server/server.h"
#include "tools/client/client_commands.h"
// After Eigen (through the cell controller): httplib's headers define macros
// that break Eigen's when they come first.
#include <httplib.h>

#include <nlohmann/json.hpp>

namespace cornerpose::server {
namespace {

namespace fs = std::filesystem;

// Two CAs, each with a server and a client certificate, made once.
struct Certificates {
  fs::path good;   // ca.pem, server.pem/.key, client.pem/.key
  fs::path other;  // the same from an unrelated CA
};

const Certificates& Certs() {
  static const Certificates* certs = [] {
    const fs::path root = fs::temp_directory_path() / ("cornerpose_tls_" + std::to_string(getpid()));
    auto* c = new Certificates{root / "good", root / "other"};
    for (const fs::path& dir : {c->good, c->other}) {
      const std::string command = std::string(CORNERPOSE_SOURCE_DIR) + "/scripts/make-certs '" +
                                  dir.string() + "' localhost 127.0.0.1 > /dev/null";
      EXPECT_EQ(std::system(command.c_str()), 0) << command;
    }
    return c;
  }();
  return *certs;
}

std::string In(const fs::path& dir, const char* name) { return (dir / name).string(); }

ServerTlsFiles MutualTls() {
  const fs::path& d = Certs().good;
  return {.cert = In(d, "server.pem"), .key = In(d, "server.key"), .client_ca = In(d, "ca.pem")};
}

ClientTlsFiles ClientOf(const fs::path& dir, bool with_cert = true) {
  ClientTlsFiles files;
  files.ca = In(Certs().good, "ca.pem");
  if (with_cert) {
    files.cert = In(dir, "client.pem");
    files.key = In(dir, "client.key");
  }
  return files;
}

std::shared_ptr<grpc::Channel> Channel(int port, const ClientTlsFiles& tls) {
  grpc::ChannelArguments args;
  absl::StatusOr<std::shared_ptr<grpc::ChannelCredentials>> credentials =
      MakeChannelCredentials(tls, &args);
  EXPECT_TRUE(credentials.ok()) << credentials.status();
  return grpc::CreateCustomChannel("127.0.0.1:" + std::to_string(port), *credentials, args);
}

grpc::Status CheckHealth(const std::shared_ptr<grpc::Channel>& channel) {
  auto stub = grpc::health::v1::Health::NewStub(channel);
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(5));
  grpc::health::v1::HealthCheckResponse response;
  grpc::Status s = stub->Check(&context, grpc::health::v1::HealthCheckRequest(), &response);
  if (s.ok() && response.status() != grpc::health::v1::HealthCheckResponse::SERVING) {
    return grpc::Status(grpc::StatusCode::UNAVAILABLE, "not serving");
  }
  return s;
}

grpc::Status DetectEmpty(const std::shared_ptr<grpc::Channel>& channel) {
  auto stub = v1::PerceptionService::NewStub(channel);
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(5));
  v1::DetectRequest request;
  request.mutable_cloud();
  request.set_box_model("brick");
  v1::DetectResponse response;
  return stub->Detect(&context, request, &response);
}

std::unique_ptr<RunningServer> StartTls(const ServerTlsFiles& tls) {
  ServerOptions options;
  options.listen_address = "127.0.0.1:0";
  options.tls_cert = tls.cert;
  options.tls_key = tls.key;
  options.tls_client_ca = tls.client_ca;
  absl::StatusOr<std::unique_ptr<RunningServer>> server = StartServer(options);
  EXPECT_TRUE(server.ok()) << server.status();
  return server.ok() ? *std::move(server) : nullptr;
}

TEST(ServerTlsTest, MutualTlsServesAValidClientCertificateOnly) {
  std::unique_ptr<RunningServer> server = StartTls(MutualTls());
  ASSERT_NE(server, nullptr);
  const int port = server->port();

  grpc::Status s = DetectEmpty(Channel(port, ClientOf(Certs().good)));
  EXPECT_TRUE(s.ok()) << s.error_message();
  EXPECT_TRUE(CheckHealth(Channel(port, ClientOf(Certs().good))).ok());

  s = DetectEmpty(Channel(port, ClientOf(Certs().good, /*with_cert=*/false)));
  EXPECT_EQ(s.error_code(), grpc::StatusCode::UNAVAILABLE) << "no client certificate";
  s = DetectEmpty(Channel(port, ClientOf(Certs().other)));
  EXPECT_EQ(s.error_code(), grpc::StatusCode::UNAVAILABLE) << "another CA's certificate";

  // Plaintext to the TLS port: a clean failure within the deadline.
  const auto t0 = std::chrono::steady_clock::now();
  s = DetectEmpty(Channel(port, {}));
  EXPECT_EQ(s.error_code(), grpc::StatusCode::UNAVAILABLE) << s.error_message();
  EXPECT_LT(std::chrono::steady_clock::now() - t0, std::chrono::seconds(6));

  // And the server is none the worse.
  s = DetectEmpty(Channel(port, ClientOf(Certs().good)));
  EXPECT_TRUE(s.ok()) << s.error_message();
}

TEST(ServerTlsTest, TlsWithoutClientCaChecksTheServerOnly) {
  const fs::path& d = Certs().good;
  ServerTlsFiles server_only;  // no client_ca: client certificates not asked for
  server_only.cert = In(d, "server.pem");
  server_only.key = In(d, "server.key");
  std::unique_ptr<RunningServer> server = StartTls(server_only);
  ASSERT_NE(server, nullptr);
  grpc::Status s = DetectEmpty(Channel(server->port(), ClientOf(d, /*with_cert=*/false)));
  EXPECT_TRUE(s.ok()) << s.error_message();
  // A client that trusts another CA refuses this server.
  ClientTlsFiles wrong_ca;
  wrong_ca.ca = In(Certs().other, "ca.pem");
  s = DetectEmpty(Channel(server->port(), wrong_ca));
  EXPECT_EQ(s.error_code(), grpc::StatusCode::UNAVAILABLE) << s.error_message();
}

TEST(ServerTlsTest, BadTlsFilesAreRefusedAtStart) {
  ServerOptions options;
  options.listen_address = "127.0.0.1:0";
  options.tls_cert = "/nonexistent/server.pem";
  options.tls_key = "/nonexistent/server.key";
  absl::StatusOr<std::unique_ptr<RunningServer>> server = StartServer(options);
  ASSERT_FALSE(server.ok());
  EXPECT_EQ(server.status().code(), absl::StatusCode::kNotFound);
  EXPECT_NE(server.status().message().find("tls_cert"), std::string::npos) << server.status();

  options.tls_cert = In(Certs().good, "server.pem");
  options.tls_key = "";
  server = StartServer(options);
  ASSERT_FALSE(server.ok());
  EXPECT_EQ(server.status().code(), absl::StatusCode::kInvalidArgument);
}

TEST(ServerTlsTest, StatusServiceOfTheDaemonTakesMutualTls) {
  // Health only: the status handlers are not called, so no cell is needed.
  absl::StatusOr<std::unique_ptr<robot_client::StatusServer>> status =
      robot_client::StartStatusServer("127.0.0.1:0", nullptr, MutualTls());
  ASSERT_TRUE(status.ok()) << status.status();
  const int port = (*status)->port();
  EXPECT_TRUE(CheckHealth(Channel(port, ClientOf(Certs().good))).ok());
  EXPECT_EQ(CheckHealth(Channel(port, ClientOf(Certs().other))).error_code(),
            grpc::StatusCode::UNAVAILABLE);
  EXPECT_EQ(CheckHealth(Channel(port, {})).error_code(), grpc::StatusCode::UNAVAILABLE);
}

// The web view's /api/cell asks the daemon's status service over mutual
// TLS when given the files, as the daemon serves it; without them it shows
// the daemon as unreachable (a TLS port refuses plaintext) and keeps
// serving. The daemon here is a real controller, not running: its status
// is the one it starts with.
TEST(ServerTlsTest, WebViewReadsTheDaemonsStatusOverMutualTls) {
  robot_client::PerceptionSubscriber perception({});
  robot_client::RobotClientOptions cell_options;
  cell_options.dry_run = true;
  robot_client::CellController cell(cell_options, {}, &perception);
  absl::StatusOr<std::unique_ptr<robot_client::StatusServer>> status =
      robot_client::StartStatusServer("127.0.0.1:0", &cell, MutualTls());
  ASSERT_TRUE(status.ok()) << status.status();
  const std::string daemon = "127.0.0.1:" + std::to_string((*status)->port());

  auto cell_json = [&](const ClientTlsFiles& tls) {
    ServerOptions options;
    options.listen_address = "127.0.0.1:0";
    options.http.listen_address = "127.0.0.1:0";
    options.http.cell_status_address = daemon;
    options.http.cell_status_tls_ca = tls.ca;
    options.http.cell_status_tls_cert = tls.cert;
    options.http.cell_status_tls_key = tls.key;
    absl::StatusOr<std::unique_ptr<RunningServer>> server = StartServer(options);
    EXPECT_TRUE(server.ok()) << server.status();
    if (!server.ok()) return nlohmann::json();
    httplib::Client http("127.0.0.1", (*server)->http_port());
    httplib::Result res = http.Get("/api/cell");
    EXPECT_TRUE(res && res->status == 200);
    return res ? nlohmann::json::parse(res->body, nullptr, false) : nlohmann::json();
  };

  const nlohmann::json secure = cell_json(ClientOf(Certs().good));
  EXPECT_EQ(secure["reachable"], true) << secure.dump();
  EXPECT_EQ(secure["dry_run"], true) << secure.dump();
  EXPECT_TRUE(secure["state"].is_string()) << secure.dump();

  for (const ClientTlsFiles& tls : {ClientTlsFiles{}, ClientOf(Certs().other)}) {
    const nlohmann::json refused = cell_json(tls);
    EXPECT_EQ(refused["reachable"], false) << refused.dump();
    EXPECT_TRUE(refused["error"].is_string()) << refused.dump();
  }
}

TEST(ServerTlsTest, BadCellStatusTlsFilesAreRefusedAtStart) {
  ServerOptions options;
  options.listen_address = "127.0.0.1:0";
  options.http.listen_address = "127.0.0.1:0";
  options.http.cell_status_address = "127.0.0.1:1";
  options.http.cell_status_tls_ca = "/nonexistent/ca.pem";
  absl::StatusOr<std::unique_ptr<RunningServer>> server = StartServer(options);
  ASSERT_FALSE(server.ok());
  EXPECT_EQ(server.status().code(), absl::StatusCode::kNotFound);
  EXPECT_NE(server.status().message().find("cell status TLS"), std::string::npos)
      << server.status();
  EXPECT_NE(server.status().message().find("/nonexistent/ca.pem"), std::string::npos)
      << server.status();
}

TEST(ServerTlsTest, CliHealthTakesTlsFlags) {
  std::unique_ptr<RunningServer> server = StartTls(MutualTls());
  ASSERT_NE(server, nullptr);
  const std::string address = "127.0.0.1:" + std::to_string(server->port());
  const fs::path& d = Certs().good;
  EXPECT_EQ(tools::RunClientHealth({"--server", address, "--quiet", "--tls_ca", In(d, "ca.pem"),
                                    "--tls_cert", In(d, "client.pem"), "--tls_key",
                                    In(d, "client.key")}),
            0);
  EXPECT_EQ(tools::RunClientHealth(
                {"--server", address, "--quiet", "--tls_ca", In(d, "ca.pem"), "--deadline_ms", "2000"}),
            1);
  EXPECT_EQ(tools::RunClientHealth({"--server", address, "--quiet", "--deadline_ms", "2000"}), 1);
}

TEST(ServerTlsTest, ReflectionOffAnswersUnimplemented) {
  ServerOptions options;
  options.listen_address = "127.0.0.1:0";
  options.enable_reflection = false;
  absl::StatusOr<std::unique_ptr<RunningServer>> server = StartServer(options);
  ASSERT_TRUE(server.ok()) << server.status();
  std::shared_ptr<grpc::Channel> channel = Channel((*server)->port(), {});
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(5));
  const grpc::internal::RpcMethod method(
      "/grpc.reflection.v1alpha.ServerReflection/ServerReflectionInfo",
      grpc::internal::RpcMethod::BIDI_STREAMING);
  std::unique_ptr<grpc::ClientReaderWriter<grpc::ByteBuffer, grpc::ByteBuffer>> stream(
      grpc::internal::ClientReaderWriterFactory<grpc::ByteBuffer, grpc::ByteBuffer>::Create(
          channel.get(), method, &context));
  grpc::Slice empty(std::string(""));
  stream->Write(grpc::ByteBuffer(&empty, 1));
  stream->WritesDone();
  grpc::ByteBuffer reply;
  EXPECT_FALSE(stream->Read(&reply));
  EXPECT_EQ(stream->Finish().error_code(), grpc::StatusCode::UNIMPLEMENTED);
  // The service itself still answers.
  EXPECT_TRUE(DetectEmpty(channel).ok());
}

}  // namespace
}  // namespace cornerpose::server
