// The server's HTTP port against a real server on loopback: the JSON API of
// web/README.md on a recorded frame, the frame's image and cloud, the event
// stream, errors, the embedded page, /api/cell and /metrics moving as
// requests are made.
#include "server/http/http_server.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>

#include "server/server.h"
// After Eigen (through server.h): httplib.h pulls in <resolv.h>, whose _res
// macro breaks Eigen's headers included after it.
#include <httplib.h>  // NOLINT(build/include_order)

namespace cornerpose::server {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

const fs::path kCartonFrames = fs::path(CORNERPOSE_SOURCE_DIR) / "data/frames/carton_s";

// A directory holding one recorded frame, so every frame of a source on it
// is the same file; one per process (ctest runs this binary's tests side by
// side, and one rewriting the frame while another reads it broke the PNG).
fs::path OneFrameDirectory() {
  const fs::path dir =
      fs::path(::testing::TempDir()) / ("http_one_frame_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  for (const char* name : {"heap_001.png", "intrinsics.txt"}) {
    fs::copy_file(kCartonFrames / name, dir / name, fs::copy_options::overwrite_existing);
  }
  return dir;
}

class HttpServerTest : public ::testing::Test {
 protected:
  void Start(const std::string& cell_status_address = "") {
    ServerOptions options;
    options.listen_address = "127.0.0.1:0";
    options.http.listen_address = "127.0.0.1:0";
    options.http.cell_status_address = cell_status_address;
    options.http.view_max_rate_hz = 10;
    SourceSpec spec;
    spec.name = "one";
    spec.directory = OneFrameDirectory().string();
    spec.fps = 10;
    options.sources.push_back(spec);
    absl::StatusOr<std::unique_ptr<RunningServer>> server = StartServer(options);
    ASSERT_TRUE(server.ok()) << server.status();
    server_ = *std::move(server);
    ASSERT_GT(server_->http_port(), 0);
    client_ = std::make_unique<httplib::Client>("127.0.0.1", server_->http_port());
    client_->set_read_timeout(30, 0);
  }

  json GetJson(const std::string& path, int expected_status = 200) {
    httplib::Result res = client_->Get(path.c_str());
    EXPECT_TRUE(res) << path << ": " << httplib::to_string(res.error());
    if (!res) return json();
    EXPECT_EQ(res->status, expected_status) << path << ": " << res->body;
    EXPECT_EQ(res->get_header_value("Content-Type"), "application/json") << path;
    return json::parse(res->body, nullptr, /*allow_exceptions=*/false);
  }

  std::string Metrics() {
    httplib::Result res = client_->Get("/metrics");
    EXPECT_TRUE(res && res->status == 200);
    return res ? res->body : "";
  }

  std::unique_ptr<RunningServer> server_;
  std::unique_ptr<httplib::Client> client_;
};

TEST_F(HttpServerTest, LatestIsADetectionOnTheNewestFrameWithItsImageAndCloud) {
  Start();
  const json d = GetJson("/api/sources/one/latest");
  ASSERT_TRUE(d.is_object());
  EXPECT_EQ(d["source"], "one");
  EXPECT_GT(d["frame_id"].get<uint64_t>(), 0u);
  EXPECT_EQ(d["box_model"], "carton_s");
  EXPECT_EQ(d["box_dims"], json::array({0.3, 0.2, 0.15}));
  EXPECT_EQ(d["intrinsics"]["width"], 640);
  EXPECT_EQ(d["image"]["kind"], "depth");
  // The recorded heap has cartons on it; each box has a 4x4 pose.
  ASSERT_FALSE(d["boxes"].empty());
  for (const json& box : d["boxes"]) {
    ASSERT_EQ(box["camera_T_box"].size(), 4u);
    EXPECT_EQ(box["camera_T_box"][3], json::array({0.0, 0.0, 0.0, 1.0}));
    EXPECT_GT(box["score"].get<double>(), 0.0);
  }
  EXPECT_FALSE(d["segments"].empty());
  EXPECT_EQ(d["edge_points"].size(), 3 * d["num_edge_points"].get<size_t>());
  EXPECT_GT(d["timings_ms"]["total"].get<double>(), 0.0);

  httplib::Result image = client_->Get(d["image"]["url"].get<std::string>().c_str());
  ASSERT_TRUE(image);
  EXPECT_EQ(image->status, 200);
  EXPECT_EQ(image->get_header_value("Content-Type"), "image/png");
  EXPECT_EQ(image->body.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));

  httplib::Result cloud = client_->Get(d["cloud"]["url"].get<std::string>().c_str());
  ASSERT_TRUE(cloud);
  EXPECT_EQ(cloud->status, 200);
  ASSERT_GE(cloud->body.size(), 12u);
  EXPECT_EQ(cloud->body.substr(0, 4), "CPC1");
  uint32_t count = 0;
  std::memcpy(&count, cloud->body.data() + 4, 4);
  EXPECT_EQ(count, d["cloud"]["points"].get<uint32_t>());
  EXPECT_GT(count, 1000u);
  EXPECT_EQ(cloud->body.size(), 12u + 12u * count);
}

TEST_F(HttpServerTest, ABoxNamedByThePageIsDetectedForIt) {
  Start();
  const json d = GetJson("/api/sources/one/latest?box=0.19,0.09,0.057");
  EXPECT_EQ(d["box_model"], "0.19,0.09,0.057");
  EXPECT_EQ(d["box_dims"], json::array({0.19, 0.09, 0.057}));
}

TEST_F(HttpServerTest, ErrorsAreJsonWithTheStatusTheSpecNames) {
  Start();
  EXPECT_EQ(GetJson("/api/sources/nowhere/latest", 404)["error"], "unknown source 'nowhere'");
  EXPECT_NE(GetJson("/api/sources/one/latest?box=shoebox", 400)["error"].get<std::string>().find(
                "shoebox"),
            std::string::npos);
  EXPECT_TRUE(GetJson("/api/sources/one/frames/999999/image.png", 404).contains("error"));
  EXPECT_TRUE(GetJson("/api/sources/nowhere/events", 404).contains("error"));
  EXPECT_TRUE(GetJson("/no/such/page", 404).contains("error"));
}

TEST_F(HttpServerTest, SourcesListTheStateAndRate) {
  Start();
  GetJson("/api/sources/one/latest");  // a frame has arrived
  const json listed = GetJson("/api/sources");
  ASSERT_EQ(listed["sources"].size(), 1u);
  const json& s = listed["sources"][0];
  EXPECT_EQ(s["name"], "one");
  EXPECT_EQ(s["state"], "RUNNING");
  EXPECT_EQ(s["box_model"], "carton_s");
  EXPECT_GT(s["frame_id"].get<uint64_t>(), 0u);
  EXPECT_TRUE(s["frame_age_s"].is_number());
  EXPECT_TRUE(s["detection_ms"].is_number());
}

TEST_F(HttpServerTest, EventsPushDetectionsOfNewFrames) {
  Start();
  std::string received;
  std::vector<uint64_t> ids;
  // Reads until two detection events came (the receiver stops the stream).
  httplib::Result res =
      client_->Get("/api/sources/one/events", [&](const char* data, size_t length) {
        received.append(data, length);
        size_t at = 0;
        ids.clear();
        while ((at = received.find("event: detection\ndata: ", at)) != std::string::npos) {
          at += 23;
          const size_t end = received.find("\n\n", at);
          if (end == std::string::npos) break;
          ids.push_back(json::parse(received.substr(at, end - at))["frame_id"].get<uint64_t>());
        }
        return ids.size() < 2;
      });
  ASSERT_EQ(ids.size(), 2u) << received.substr(0, 300);
  EXPECT_LT(ids[0], ids[1]);  // a newer frame each time
  EXPECT_NE(received.find("event: state\ndata: {"), std::string::npos);
}

TEST_F(HttpServerTest, ThePageAndItsFilesComeFromTheServer) {
  Start();
  for (const char* path : {"/", "/sources/one"}) {
    httplib::Result res = client_->Get(path);
    ASSERT_TRUE(res);
    EXPECT_EQ(res->status, 200) << path;
    EXPECT_EQ(res->get_header_value("Content-Type"), "text/html; charset=utf-8") << path;
    EXPECT_NE(res->body.find("<html"), std::string::npos) << path;
  }
}

TEST_F(HttpServerTest, CellIsNotConfiguredOrUnreachable) {
  Start();
  EXPECT_EQ(GetJson("/api/cell"), json({{"configured", false}}));
  server_.reset();
  // Port 1 on loopback: nothing listens there.
  Start("127.0.0.1:1");
  const json cell = GetJson("/api/cell");
  EXPECT_EQ(cell["configured"], true);
  EXPECT_EQ(cell["reachable"], false);
  EXPECT_TRUE(cell["error"].is_string());
}

TEST_F(HttpServerTest, BadHttpOptionsAreRefusedByName) {
  ServerOptions options;
  options.listen_address = "127.0.0.1:0";
  options.http.listen_address = "127.0.0.1:0";
  options.http.frames_kept = 0;
  absl::StatusOr<std::unique_ptr<RunningServer>> server = StartServer(options);
  ASSERT_FALSE(server.ok());
  EXPECT_NE(server.status().message().find("frames_kept"), std::string::npos);
  options.http.frames_kept = 4;
  options.http.listen_address = "127.0.0.1:http";
  server = StartServer(options);
  ASSERT_FALSE(server.ok());
  EXPECT_EQ(server.status().code(), absl::StatusCode::kInvalidArgument);
  options.http.listen_address = "127.0.0.1:0";
  options.http.view_box = "shoebox";
  server = StartServer(options);
  ASSERT_FALSE(server.ok());
  EXPECT_NE(server.status().message().find("shoebox"), std::string::npos);
}

// HTTPS with the same PEM files as a gRPC TLS port: a certificate made at
// test time with openssl, verified by the client.
TEST(HttpsTest, ServesOverTlsWithTheGivenCertificate) {
  const fs::path dir = fs::path(::testing::TempDir()) / "http_tls";
  fs::create_directories(dir);
  const std::string cert = (dir / "cert.pem").string();
  const std::string key = (dir / "key.pem").string();
  const std::string command =
      "openssl req -x509 -newkey rsa:2048 -nodes -days 2 -subj /CN=127.0.0.1 "
      "-addext subjectAltName=IP:127.0.0.1 -keyout " +
      key + " -out " + cert + " 2>/dev/null";
  ASSERT_EQ(std::system(command.c_str()), 0) << command;

  DetectionPool pool(1);
  const BoxModels models;
  HttpOptions options;
  options.listen_address = "127.0.0.1:0";
  absl::StatusOr<std::unique_ptr<HttpServer>> server =
      HttpServer::Start(options, {cert, key}, {}, &pool, DetectorOptions{}, &models, nullptr);
  ASSERT_TRUE(server.ok()) << server.status();

  httplib::SSLClient client("127.0.0.1", (*server)->port());
  client.set_ca_cert_path(cert.c_str());
  client.enable_server_certificate_verification(true);
  httplib::Result res = client.Get("/api/sources");
  ASSERT_TRUE(res) << httplib::to_string(res.error());
  EXPECT_EQ(res->status, 200);
  EXPECT_EQ(res->body, R"({"sources":[]})");
  // Plain HTTP to the HTTPS port gets no answer.
  httplib::Client plain("127.0.0.1", (*server)->port());
  plain.set_read_timeout(5, 0);
  httplib::Result refused = plain.Get("/api/sources");
  EXPECT_TRUE(!refused || refused->status != 200);

  // A key that is not a key: refused at start, naming the files.
  absl::StatusOr<std::unique_ptr<HttpServer>> bad =
      HttpServer::Start(options, {cert, cert}, {}, &pool, DetectorOptions{}, &models, nullptr);
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.status().code(), absl::StatusCode::kUnavailable);
  EXPECT_NE(bad.status().message().find("cert.pem"), std::string::npos);
}

// A value in the exposition text: the line "NAME{LABELS} VALUE" (0 when absent).
double Sample(const std::string& text, const std::string& series) {
  const size_t at = text.find("\n" + series + " ");
  if (at == std::string::npos) return 0;
  return std::stod(text.substr(at + series.size() + 2));
}

// An HTTP request is counted by cpp-httplib's logger, which runs after the
// response is written: a client that has its answer may read the metrics a
// moment before it is counted. The test reads them until the 404 shows (up
// to 2 s), then checks every series on that reading.
TEST_F(HttpServerTest, MetricsCountViewDetectionsAndHttpRequests) {
  Start();
  const std::string not_found =
      R"(cornerpose_http_requests_total{route="/api/sources/{name}/latest",status="404"})";
  const std::string before = Metrics();
  GetJson("/api/sources/one/latest");
  GetJson("/api/sources/nowhere/latest", 404);
  std::string after = Metrics();
  for (int i = 0; i < 100 && Sample(after, not_found) < Sample(before, not_found) + 1; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    after = Metrics();
  }
  EXPECT_GE(Sample(after, R"(cornerpose_detections_total{origin="view"})"),
            Sample(before, R"(cornerpose_detections_total{origin="view"})") + 1);
  EXPECT_EQ(Sample(after, not_found), Sample(before, not_found) + 1);
  EXPECT_EQ(Sample(after, R"(cornerpose_source_state{source="one",state="RUNNING"})"), 1);
  EXPECT_GE(Sample(after, R"(cornerpose_detection_stage_seconds_count{stage="total"})"), 1);
}

}  // namespace
}  // namespace cornerpose::server
