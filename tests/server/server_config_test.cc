// LoadServerConfig: every shipped configuration under deploy/ loads and
// starts a real server (on 127.0.0.1:0) whose sources come up RUNNING, and
// bad files fail with the right status.
#include "server/config/server_config.h"

#include <gmock/gmock.h>
#include <grpcpp/create_channel.h>
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "cornerpose/v1/perception_service.grpc.pb.h"
#include "server/server.h"

namespace cornerpose::server {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

// Every server configuration shipped under deploy/: server*.textproto (the
// daemon's robot_client*.textproto are tested with the daemon).
std::vector<fs::path> DeployConfigs() {
  std::vector<fs::path> files;
  for (const fs::directory_entry& entry :
       fs::recursive_directory_iterator(fs::path(CORNERPOSE_SOURCE_DIR) / "deploy")) {
    if (entry.is_regular_file() && entry.path().extension() == ".textproto" &&
        entry.path().filename().string().rfind("server", 0) == 0) {
      files.push_back(entry.path());
    }
  }
  return files;
}

// The state of every source ListSources reports once none is STARTING (or
// 10 s pass).
std::vector<v1::Source> SettledSources(v1::PerceptionService::Stub& stub) {
  v1::ListSourcesResponse response;
  for (int i = 0; i < 1000; ++i) {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
    response.Clear();
    const grpc::Status s = stub.ListSources(&context, v1::ListSourcesRequest(), &response);
    EXPECT_TRUE(s.ok()) << s.error_message();
    bool starting = false;
    for (const v1::Source& source : response.sources()) {
      starting = starting || source.state() == v1::SOURCE_STATE_STARTING;
    }
    if (!starting) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return {response.sources().begin(), response.sources().end()};
}

TEST(ServerConfigTest, EveryDeployConfigStartsAServerWithItsSources) {
  const std::vector<fs::path> files = DeployConfigs();
  ASSERT_FALSE(files.empty()) << "no server*.textproto under deploy/";
  for (const fs::path& file : files) {
    SCOPED_TRACE(file.string());
    absl::StatusOr<ServerOptions> options = LoadServerConfig(file.string());
    ASSERT_TRUE(options.ok()) << options.status();
    ASSERT_FALSE(options->sources.empty());
    options->listen_address = "127.0.0.1:0";
    // The file's HTTP port, on a free port (tests run in parallel).
    if (!options->http.listen_address.empty()) options->http.listen_address = "127.0.0.1:0";
    absl::StatusOr<std::unique_ptr<RunningServer>> server = StartServer(*options);
    ASSERT_TRUE(server.ok()) << server.status();
    auto stub = v1::PerceptionService::NewStub(grpc::CreateChannel(
        "127.0.0.1:" + std::to_string((*server)->port()), grpc::InsecureChannelCredentials()));
    const std::vector<v1::Source> listed = SettledSources(*stub);
    ASSERT_EQ(listed.size(), options->sources.size());
    for (const SourceSpec& spec : options->sources) {
      bool found = false;
      for (const v1::Source& source : listed) {
        if (source.name() != spec.name) continue;
        found = true;
        EXPECT_EQ(source.state(), v1::SOURCE_STATE_RUNNING)
            << spec.name << ": " << source.state_reason();
      }
      EXPECT_TRUE(found) << spec.name;
    }
  }
}

TEST(ServerConfigTest, ShippedConfigHasTheDocumentedValues) {
  const fs::path file = fs::path(CORNERPOSE_SOURCE_DIR) / "deploy/config/server.textproto";
  absl::StatusOr<ServerOptions> options = LoadServerConfig(file.string());
  ASSERT_TRUE(options.ok()) << options.status();
  EXPECT_EQ(options->listen_address, "0.0.0.0:50051");
  EXPECT_EQ(options->max_message_bytes, 64 * 1024 * 1024);
  EXPECT_EQ(options->max_concurrent_detections, 2);
  EXPECT_EQ(options->max_connection_age_s, 300);
  ASSERT_EQ(options->sources.size(), 3u);
  // The demo cell's camera, which deploy/config/robot_client.textproto uses.
  EXPECT_EQ(options->sources[0].name, "cell");
  EXPECT_TRUE(fs::equivalent(options->sources[0].directory,
                             fs::path(CORNERPOSE_SOURCE_DIR) / "data/frames/cell"));
  EXPECT_EQ(options->sources[0].fps, 5.0);
  EXPECT_TRUE(options->sources[0].loop);
  EXPECT_EQ(options->sources[1].name, "carton_s");
  EXPECT_TRUE(fs::equivalent(options->sources[1].directory,
                             fs::path(CORNERPOSE_SOURCE_DIR) / "data/frames/carton_s"));
  EXPECT_EQ(options->sources[1].fps, 5.0);
  EXPECT_TRUE(options->sources[1].loop);
  EXPECT_EQ(options->sources[2].name, "brick");
  EXPECT_EQ(options->sources[2].fps, 2.0);
  EXPECT_TRUE(options->sources[2].loop);
}

// Writes `text` to a fresh file in the test's temporary directory.
std::string WriteConfig(const std::string& name, const std::string& text) {
  const fs::path path = fs::path(::testing::TempDir()) / name;
  std::ofstream(path) << text;
  return path.string();
}

TEST(ServerConfigTest, MissingFileIsNotFound) {
  const absl::StatusOr<ServerOptions> options =
      LoadServerConfig("/nonexistent/cornerpose/server.textproto");
  EXPECT_EQ(options.status().code(), absl::StatusCode::kNotFound) << options.status();
}

TEST(ServerConfigTest, SyntaxErrorIsInvalidArgumentNamingTheFile) {
  const std::string path =
      WriteConfig("syntax_error.textproto", "listen_address: \"127.0.0.1:0\"\nsources { name: }\n");
  const absl::StatusOr<ServerOptions> options = LoadServerConfig(path);
  EXPECT_EQ(options.status().code(), absl::StatusCode::kInvalidArgument) << options.status();
  EXPECT_THAT(options.status().message(), HasSubstr(path));
  EXPECT_THAT(options.status().message(), HasSubstr("2:"));  // the parser's line
}

TEST(ServerConfigTest, DuplicateSourceNameIsInvalidArgument) {
  const std::string path = WriteConfig("duplicate.textproto",
                                       "sources { name: \"a\" directory: \"x\" }\n"
                                       "sources { name: \"a\" directory: \"y\" }\n");
  const absl::StatusOr<ServerOptions> options = LoadServerConfig(path);
  EXPECT_EQ(options.status().code(), absl::StatusCode::kInvalidArgument) << options.status();
  EXPECT_THAT(options.status().message(), HasSubstr("duplicate"));
}

TEST(ServerConfigTest, BadValuesAreInvalidArgument) {
  for (const std::string text : {"sources { name: \"\" directory: \"x\" }",
                                 "sources { name: \"a\" directory: \"x\" fps: 0 }",
                                 "sources { name: \"a\" directory: \"x\" fps: -1 }",
                                 "max_message_bytes: 0", "max_concurrent_detections: -2",
                                 "box_models { key: \"tiny\" value { l: 0.1 b: 0 h: 0.1 } }",
                                 "max_connection_age_s: -1", "max_connection_age_s: 90000"}) {
    const absl::StatusOr<ServerOptions> options =
        LoadServerConfig(WriteConfig("bad.textproto", text));
    EXPECT_EQ(options.status().code(), absl::StatusCode::kInvalidArgument) << text;
  }
}

TEST(ServerConfigTest, TheSimulatedPalletCellTilesFacesWithNoSeam) {
  const fs::path file =
      fs::path(CORNERPOSE_SOURCE_DIR) / "deploy/config/sim_server_pallet.textproto";
  absl::StatusOr<ServerOptions> options = LoadServerConfig(file.string());
  ASSERT_TRUE(options.ok()) << options.status();
  EXPECT_TRUE(options->detector.refinement.tile_uncued_sides);
  ASSERT_EQ(options->sources.size(), 1u);
  EXPECT_EQ(options->sources[0].name, "sim");
  // The heap and bin cell's keeps the default.
  options = LoadServerConfig(
      (fs::path(CORNERPOSE_SOURCE_DIR) / "deploy/config/sim_server.textproto").string());
  ASSERT_TRUE(options.ok()) << options.status();
  EXPECT_FALSE(options->detector.refinement.tile_uncued_sides);
}

TEST(ServerConfigTest, BoxModelsAndDetectorDefaultsReachTheOptions) {
  const std::string path =
      WriteConfig("models.textproto",
                  "box_models { key: \"crate\" value { l: 0.5 b: 0.4 h: 0.3 } }\n"
                  "detector_defaults { edge_threshold: 0.4 edge_radius_m: 0.02 }\n");
  const absl::StatusOr<ServerOptions> options = LoadServerConfig(path);
  ASSERT_TRUE(options.ok()) << options.status();
  ASSERT_EQ(options->box_models.count("crate"), 1u);
  EXPECT_EQ(options->box_models.at("crate").h, 0.3);
  EXPECT_EQ(options->detector.edge_points.threshold, 0.4);
  EXPECT_EQ(options->detector.edge_points.radius_m, 0.02);
  // Untouched parameters keep the detector's defaults.
  EXPECT_EQ(options->detector.segments.ransac_threshold_m,
            DetectorOptions{}.segments.ransac_threshold_m);
  EXPECT_FALSE(options->detector.refinement.tile_uncued_sides);

  const absl::StatusOr<ServerOptions> bad = LoadServerConfig(
      WriteConfig("bad_defaults.textproto", "detector_defaults { edge_radius_m: -1 }\n"));
  EXPECT_EQ(bad.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(bad.status().message(), HasSubstr("detector_defaults"));
}

TEST(ServerConfigTest, UnsetFieldsTakeServerOptionsDefaults) {
  const std::string path =
      WriteConfig("defaults.textproto", "sources { name: \"a\" directory: \"frames\" }\n");
  const absl::StatusOr<ServerOptions> options = LoadServerConfig(path);
  ASSERT_TRUE(options.ok()) << options.status();
  const ServerOptions defaults;
  EXPECT_EQ(options->listen_address, defaults.listen_address);
  EXPECT_EQ(options->max_message_bytes, defaults.max_message_bytes);
  EXPECT_EQ(options->max_concurrent_detections, defaults.max_concurrent_detections);
  EXPECT_EQ(options->max_connection_age_s, 0);
  EXPECT_EQ(options->http.listen_address, kDefaultHttpListen);
  EXPECT_EQ(options->http.cell_status_address, "");
  EXPECT_EQ(options->http.view_box, HttpOptions{}.view_box);
  ASSERT_EQ(options->sources.size(), 1u);
  EXPECT_EQ(options->sources[0].fps, SourceSpec{}.fps);
  EXPECT_TRUE(options->sources[0].loop);
  // Relative to the file's directory.
  EXPECT_EQ(options->sources[0].directory, (fs::path(path).parent_path() / "frames").string());
}

TEST(ServerConfigTest, HttpFieldsAreRead) {
  const std::string path = WriteConfig(
      "http.textproto",
      "http_listen: \"\"\ncell_status_address: \"10.0.0.5:50061\"\nview_box: \"brick\"\n");
  const absl::StatusOr<ServerOptions> options = LoadServerConfig(path);
  ASSERT_TRUE(options.ok()) << options.status();
  EXPECT_EQ(options->http.listen_address, "");  // set empty: no HTTP port
  EXPECT_EQ(options->http.cell_status_address, "10.0.0.5:50061");
  EXPECT_EQ(options->http.view_box, "brick");
}

TEST(ServerConfigTest, CellStatusTlsPathsAreRelativeToTheFile) {
  const std::string path = WriteConfig(
      "cell_tls.textproto",
      "cell_status_address: \"cell:50061\"\ncell_status_tls_ca: \"certs/ca.pem\"\n"
      "cell_status_tls_cert: \"/etc/cp/client.pem\"\ncell_status_tls_key: \"client.key\"\n"
      "cell_status_tls_server_name: \"cell.internal\"\n");
  const absl::StatusOr<ServerOptions> options = LoadServerConfig(path);
  ASSERT_TRUE(options.ok()) << options.status();
  const fs::path dir = fs::path(path).parent_path();
  EXPECT_EQ(options->http.cell_status_tls_ca, (dir / "certs/ca.pem").string());
  EXPECT_EQ(options->http.cell_status_tls_cert, "/etc/cp/client.pem");
  EXPECT_EQ(options->http.cell_status_tls_key, (dir / "client.key").string());
  EXPECT_EQ(options->http.cell_status_tls_server_name, "cell.internal");
}

}  // namespace
}  // namespace cornerpose::server
