// `cornerpose client detect` against the real server on 127.0.0.1:0, through
// RunClient (the command's entry function) rather than a subprocess.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "common/io/cloud_io.h"
#include "common/perception/detector.h"
#include "server/server.h"
#include "tests/support/scene_generator.h"
#include "tools/client_command.h"

namespace cornerpose::tools {
namespace {

using ::testing::HasSubstr;

std::unique_ptr<server::RunningServer> StartLoopbackServer() {
  server::ServerOptions options;
  options.listen_address = "127.0.0.1:0";
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
  EXPECT_THAT(err, HasSubstr("cornerpose client: "));
  EXPECT_THAT(err, HasSubstr("cannot reach server"));
}

TEST(ClientTest, BadUsageIsExitCodeTwo) {
  ::testing::internal::CaptureStderr();
  EXPECT_EQ(RunClient({"detect", "--cloud", "x.pcd"}), 2);
  EXPECT_EQ(RunClient({"nonsense"}), 2);
  EXPECT_THAT(::testing::internal::GetCapturedStderr(), HasSubstr("--server is required"));
}

}  // namespace
}  // namespace cornerpose::tools
