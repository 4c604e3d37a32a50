// `cornerpose client detect|stream|sources|health` against the real server on
// 127.0.0.1:0, through RunClient (the command's entry function) rather than a
// subprocess.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "absl/time/clock.h"
#include "common/io/cloud_io.h"
#include "common/perception/detector.h"
#include "server/server.h"
#include "tests/support/scene_generator.h"
#include "tools/client_command.h"

namespace cornerpose::tools {
namespace {

using ::testing::HasSubstr;

// The bundled recorded frames, found through the source tree.
const std::string kCartonFrames = std::string(CORNERPOSE_SOURCE_DIR) + "/data/frames/carton_s";

std::unique_ptr<server::RunningServer> StartLoopbackServer(
    std::vector<server::SourceSpec> sources = {}) {
  server::ServerOptions options;
  options.listen_address = "127.0.0.1:0";
  options.sources = std::move(sources);
  absl::StatusOr<std::unique_ptr<server::RunningServer>> running = server::StartServer(options);
  EXPECT_TRUE(running.ok()) << running.status();
  return running.ok() ? *std::move(running) : nullptr;
}

std::string TempPath(const std::string& name) {
  return (std::filesystem::path(::testing::TempDir()) / name).string();
}

TEST(ClientTest, DetectWritesSameBoxesAsInProcessDetector) {
  const testing::RenderedScene scene =
      testing::Render(testing::MakeIsolatedScene({0.30, 0.20, 0.15}, 2, 1));
  DetectorOptions options;
  options.box = {0.30, 0.20, 0.15};
  absl::StatusOr<Detection> expected = DetectBoxes(scene.cloud, options);
  ASSERT_TRUE(expected.ok()) << expected.status();
  ASSERT_GT(expected->boxes.size(), 0u);

  const std::string cloud_path = TempPath("client_test_scene.pcd");
  const std::string json_path = TempPath("client_test_scene.json");
  std::filesystem::remove(json_path);
  ASSERT_TRUE(SavePcd(cloud_path, scene.cloud).ok());

  std::unique_ptr<server::RunningServer> running = StartLoopbackServer();
  ASSERT_NE(running, nullptr);
  const std::string address = "127.0.0.1:" + std::to_string(running->port());
  const int rc = RunClient({"detect", "--server", address, "--cloud", cloud_path, "--box",
                            "0.30,0.20,0.15", "--json", json_path, "--deadline_ms", "120000"});
  ASSERT_EQ(rc, 0);

  std::ifstream in(json_path);
  ASSERT_TRUE(in.good()) << json_path;
  const nlohmann::json json = nlohmann::json::parse(in);
  ASSERT_TRUE(json.contains("boxes"));
  EXPECT_EQ(json["boxes"].size(), expected->boxes.size());
  EXPECT_EQ(json["edges"].size(), expected->segments.size());
  EXPECT_EQ(json["corners"].size(), expected->corners.size());
  // The best box's score survives the round trip.
  EXPECT_NEAR(json["boxes"][0]["score"].get<double>(), expected->boxes[0].score, 1e-9);
}

TEST(ClientTest, UnreachableServerFailsQuicklyWithExitCodeOne) {
  int port = 0;
  {
    std::unique_ptr<server::RunningServer> running = StartLoopbackServer();
    ASSERT_NE(running, nullptr);
    port = running->port();
    running->Shutdown();
  }
  // Any readable cloud: the failure must come from the connection.
  const std::string cloud_path = TempPath("client_test_small.pcd");
  PointCloud cloud;
  cloud.width = 1;
  cloud.height = 1;
  cloud.xyz = {Eigen::Vector3f(0.0f, 0.0f, 1.0f)};
  ASSERT_TRUE(SavePcd(cloud_path, cloud).ok());

  ::testing::internal::CaptureStderr();
  const auto start = std::chrono::steady_clock::now();
  const int rc = RunClient({"detect", "--server", "127.0.0.1:" + std::to_string(port), "--cloud",
                            cloud_path, "--box", "brick", "--deadline_ms", "3000"});
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const std::string err = ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(rc, 1);
  EXPECT_LT(seconds, 5.0);
  EXPECT_THAT(err, HasSubstr("cornerpose client detect: "));
  EXPECT_THAT(err, HasSubstr("cannot reach server"));
}

// A box model only the server's configuration names: the client sends the
// name (it refused names it did not know itself), and draws its outputs with
// the size the server resolved it to.
TEST(ClientTest, DetectSendsABoxModelOnlyTheServerKnows) {
  const testing::RenderedScene scene =
      testing::Render(testing::MakeIsolatedScene({0.30, 0.20, 0.15}, 2, 1));
  const std::string cloud_path = TempPath("client_test_model.pcd");
  const std::string json_path = TempPath("client_test_model.json");
  std::filesystem::remove(json_path);
  ASSERT_TRUE(SavePcd(cloud_path, scene.cloud).ok());
  server::ServerOptions options;
  options.listen_address = "127.0.0.1:0";
  options.box_models["tote_carton"] = {0.30, 0.20, 0.15};
  absl::StatusOr<std::unique_ptr<server::RunningServer>> running = server::StartServer(options);
  ASSERT_TRUE(running.ok()) << running.status();
  const std::string address = "127.0.0.1:" + std::to_string((*running)->port());
  ASSERT_EQ(RunClient({"detect", "--server", address, "--cloud", cloud_path, "--box", "tote_carton",
                       "--json", json_path, "--deadline_ms", "120000"}),
            0);
  std::ifstream in(json_path);
  const nlohmann::json json = nlohmann::json::parse(in);
  EXPECT_GT(json["boxes"].size(), 0u);
  EXPECT_NEAR(json["box_dims"][0].get<double>(), 0.30, 1e-9);
  // A name neither knows is the server's NOT_FOUND-as-invalid answer.
  ::testing::internal::CaptureStderr();
  EXPECT_EQ(RunClient({"detect", "--server", address, "--cloud", cloud_path, "--box", "crate"}), 1);
  EXPECT_THAT(::testing::internal::GetCapturedStderr(), HasSubstr("unknown box model 'crate'"));
}

TEST(ClientTest, BadUsageIsExitCodeTwo) {
  ::testing::internal::CaptureStderr();
  EXPECT_EQ(RunClient({"detect", "--cloud", "x.pcd"}), 2);
  EXPECT_EQ(RunClient({"nonsense"}), 2);
  EXPECT_THAT(::testing::internal::GetCapturedStderr(), HasSubstr("--server is required"));
}

// The number of regular files in `dir` whose name ends in `ext`.
int CountFiles(const std::string& dir, const std::string& ext) {
  int n = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (entry.path().extension() == ext) ++n;
  }
  return n;
}

TEST(ClientTest, StreamPrintsAndWritesEveryFrameOfAPlayOnceSource) {
  // 6 recorded frames played once: the stream ends by itself after the last.
  std::unique_ptr<server::RunningServer> running =
      StartLoopbackServer({{.name = "bin", .directory = kCartonFrames, .fps = 10, .loop = false}});
  ASSERT_NE(running, nullptr);
  const std::string json_dir = TempPath("client_stream_json");
  const std::string png_dir = TempPath("client_stream_png");
  std::filesystem::remove_all(json_dir);
  std::filesystem::remove_all(png_dir);
  ::testing::internal::CaptureStdout();
  const int rc = RunClient({"stream", "--server", "127.0.0.1:" + std::to_string(running->port()),
                            "--source", "bin", "--box", "carton_s", "--json", json_dir, "--png",
                            png_dir, "--deadline_ms", "60000"});
  const std::string out = ::testing::internal::GetCapturedStdout();
  ASSERT_EQ(rc, 0) << out;
  // A slow client may skip frames (newest first), but it sees at least one,
  // ids only increase, and every printed frame has its files.
  EXPECT_THAT(out, HasSubstr("bin frame "));
  const int jsons = CountFiles(json_dir, ".json");
  EXPECT_GE(jsons, 1);
  EXPECT_LE(jsons, 6);
  EXPECT_EQ(CountFiles(png_dir, ".png"), jsons);
  // The last frame is always delivered: a play-once source keeps it.
  EXPECT_TRUE(std::filesystem::exists(json_dir + "/bin_6.json")) << out;
  std::ifstream in(json_dir + "/bin_6.json");
  const nlohmann::json json = nlohmann::json::parse(in);
  EXPECT_GE(json["boxes"].size(), 1u);
}

TEST(ClientTest, StreamStopsAfterFramesOnALoopingSource) {
  std::unique_ptr<server::RunningServer> running =
      StartLoopbackServer({{.name = "bin", .directory = kCartonFrames, .fps = 20, .loop = true}});
  ASSERT_NE(running, nullptr);
  ::testing::internal::CaptureStdout();
  const int rc = RunClient({"stream", "--server", "127.0.0.1:" + std::to_string(running->port()),
                            "--source", "bin", "--box", "carton_s", "--frames", "2"});
  const std::string out = ::testing::internal::GetCapturedStdout();
  EXPECT_EQ(rc, 0);
  size_t frames = 0;
  for (size_t at = out.find("bin frame "); at != std::string::npos;
       at = out.find("bin frame ", at + 1)) {
    ++frames;
  }
  EXPECT_EQ(frames, 2u) << out;
}

TEST(ClientTest, StreamFromUnknownSourceIsNotFound) {
  std::unique_ptr<server::RunningServer> running = StartLoopbackServer();
  ASSERT_NE(running, nullptr);
  ::testing::internal::CaptureStderr();
  const int rc = RunClient({"stream", "--server", "127.0.0.1:" + std::to_string(running->port()),
                            "--source", "nope", "--box", "carton_s"});
  EXPECT_EQ(rc, 1);
  EXPECT_THAT(::testing::internal::GetCapturedStderr(), HasSubstr("NOT_FOUND"));
}

TEST(ClientTest, DetectOnASourceWritesTheFrameItDetectedOn) {
  std::unique_ptr<server::RunningServer> running =
      StartLoopbackServer({{.name = "bin", .directory = kCartonFrames, .fps = 5, .loop = true}});
  ASSERT_NE(running, nullptr);
  const std::string ply_path = TempPath("client_source.ply");
  std::filesystem::remove(ply_path);
  ::testing::internal::CaptureStdout();
  const int rc =
      RunClient({"detect", "--server", "127.0.0.1:" + std::to_string(running->port()), "--source",
                 "bin", "--box", "carton_s", "--ply", ply_path, "--deadline_ms", "60000"});
  const std::string out = ::testing::internal::GetCapturedStdout();
  ASSERT_EQ(rc, 0);
  // The frame's cloud came back with it: a VGA frame's 307200 points.
  EXPECT_THAT(out, HasSubstr("307200 points"));
  EXPECT_GT(std::filesystem::file_size(ply_path), 307200u * 12);
}

TEST(ClientTest, SourcesListsStateAndHealthReportsServing) {
  std::unique_ptr<server::RunningServer> running =
      StartLoopbackServer({{.name = "bin", .directory = kCartonFrames, .fps = 5, .loop = true},
                           {.name = "broken", .directory = "/nonexistent/frames"}});
  ASSERT_NE(running, nullptr);
  const std::string address = "127.0.0.1:" + std::to_string(running->port());
  // The broken source is STARTING until its first attempt has failed (on a
  // loaded machine that can outlast the first listing): ask again for a while.
  std::string listing;
  for (int attempt = 0; attempt < 100; ++attempt) {
    ::testing::internal::CaptureStdout();
    EXPECT_EQ(RunClient({"sources", "--server", address}), 0);
    listing = ::testing::internal::GetCapturedStdout();
    if (listing.find("broken  FAILED") != std::string::npos) break;
    absl::SleepFor(absl::Milliseconds(100));
  }
  EXPECT_THAT(listing, HasSubstr("bin  "));
  EXPECT_THAT(listing, HasSubstr("broken  FAILED"));
  ::testing::internal::CaptureStdout();
  EXPECT_EQ(RunClient({"health", "--server", address}), 0);
  EXPECT_THAT(::testing::internal::GetCapturedStdout(), HasSubstr(": SERVING"));
}

TEST(ClientTest, HealthOfAStoppedServerIsExitCodeOne) {
  int port = 0;
  {
    std::unique_ptr<server::RunningServer> running = StartLoopbackServer();
    ASSERT_NE(running, nullptr);
    port = running->port();
    running->Shutdown();
  }
  ::testing::internal::CaptureStderr();
  EXPECT_EQ(RunClient({"health", "--server", "127.0.0.1:" + std::to_string(port), "--deadline_ms",
                       "500"}),
            1);
  EXPECT_THAT(::testing::internal::GetCapturedStderr(), HasSubstr("cornerpose client health: "));
}

}  // namespace
}  // namespace cornerpose::tools
