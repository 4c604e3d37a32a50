// The real server on 127.0.0.1:0 with frame sources: ListSources reports
// them, and Detect on a source runs on its newest recorded frame.
#include <grpcpp/create_channel.h>
#include <gtest/gtest.h>

#include <chrono>
#include <memory>
#include <string>
#include <thread>

#include "cornerpose/v1/perception_service.grpc.pb.h"
#include "server/server.h"
#include "tests/server/source_server_fixture.h"

namespace cornerpose::server {
namespace {

// The repository, so the test finds the bundled frames from any build dir.
const std::string kCartonFrames = std::string(CORNERPOSE_SOURCE_DIR) + "/data/frames/carton_s";

class SourceServerTest : public testing::SourceServerFixture {
 protected:
  void SetUp() override {
    ServerOptions options;
    options.sources = {{.name = "bin", .directory = kCartonFrames, .fps = 5, .loop = true},
                       {.name = "broken", .directory = "/nonexistent/frames"}};
    StartServerWith(options);
  }
};

TEST_F(SourceServerTest, ListsSourcesWithTheirState) {
  const v1::Source bin = WaitForSource("bin");
  EXPECT_EQ(bin.description(), kCartonFrames);
  EXPECT_EQ(bin.state(), v1::SOURCE_STATE_RUNNING) << bin.state_reason();
  EXPECT_FALSE(bin.live());  // recorded frames are a replay

  const v1::Source broken = WaitForSource("broken");
  EXPECT_EQ(broken.description(), "/nonexistent/frames");
  EXPECT_EQ(broken.state(), v1::SOURCE_STATE_FAILED);
  EXPECT_NE(broken.state_reason(), "");
  EXPECT_EQ(ListSources().sources_size(), 2);
}

TEST_F(SourceServerTest, DetectOnASourceFindsBoxesInItsNewestFrame) {
  v1::DetectResponse first;
  grpc::Status s = DetectOn("bin", &first);
  ASSERT_TRUE(s.ok()) << s.error_message();
  EXPECT_GT(first.boxes_size(), 0);
  EXPECT_EQ(first.source(), "bin");
  EXPECT_GT(first.frame_id(), 0u);
  EXPECT_GT(first.capture_time_unix_nanos(), 0);
  EXPECT_FALSE(first.source_live());
  // A frame directory's device time is its frame index over its rate.
  EXPECT_EQ(first.device_timestamp_us(), (first.frame_id() - 1) * 200000u);

  // At 5 fps a later request sees a later frame.
  std::this_thread::sleep_for(std::chrono::milliseconds(400));
  v1::DetectResponse second;
  s = DetectOn("bin", &second);
  ASSERT_TRUE(s.ok()) << s.error_message();
  EXPECT_GT(second.frame_id(), first.frame_id());
  EXPECT_GT(second.device_timestamp_us(), first.device_timestamp_us());
  EXPECT_GE(second.capture_time_unix_nanos(), first.capture_time_unix_nanos());
}

TEST_F(SourceServerTest, UnknownSourceIsNotFoundAndFailedSourceUnavailable) {
  v1::DetectResponse response;
  grpc::Status s = DetectOn("camera_7", &response);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_NE(s.error_message().find("unknown source 'camera_7'"), std::string::npos);

  WaitForSource("broken");
  s = DetectOn("broken", &response);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::UNAVAILABLE);
  EXPECT_NE(s.error_message().find("/nonexistent/frames"), std::string::npos) << s.error_message();

  // Still serving.
  s = DetectOn("bin", &response);
  ASSERT_TRUE(s.ok()) << s.error_message();
  EXPECT_EQ(response.source(), "bin");
  EXPECT_GT(response.boxes_size(), 0);
}

TEST_F(SourceServerTest, StreamDeliversNewFramesInOrderUntilCancelled) {
  ExpectStreamInOrderUntilCancelled("bin", 3);

  // Still serving after the cancel.
  v1::DetectResponse response;
  grpc::Status s = DetectOn("bin", &response);
  EXPECT_TRUE(s.ok()) << s.error_message();
}

TEST_F(SourceServerTest, StreamOnAnUnknownSourceIsNotFound) {
  v1::StreamDetectionsRequest request;
  request.set_source("camera_7");
  request.set_box_model("carton_s");
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
  std::unique_ptr<grpc::ClientReader<v1::DetectResponse>> reader =
      stub_->StreamDetections(&context, request);
  v1::DetectResponse response;
  EXPECT_FALSE(reader->Read(&response));
  EXPECT_EQ(reader->Finish().error_code(), grpc::StatusCode::NOT_FOUND);
}

TEST_F(SourceServerTest, ShutdownEndsAStreamThatIsStillOpen) {
  v1::StreamDetectionsRequest request;
  request.set_source("bin");
  request.set_box_model("carton_s");
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
  std::unique_ptr<grpc::ClientReader<v1::DetectResponse>> reader =
      stub_->StreamDetections(&context, request);
  v1::DetectResponse response;
  ASSERT_TRUE(reader->Read(&response));
  server_->Shutdown();  // must not wait for the stream forever
  while (reader->Read(&response)) {
  }
  EXPECT_FALSE(reader->Finish().ok());
}

// With a connection-age cap the server asks old connections to reconnect
// (how clients find new replicas) but never cuts a call in flight: a stream
// runs on well past the age, and later calls go out on a fresh connection.
class ConnectionAgeTest : public testing::SourceServerFixture {
 protected:
  void SetUp() override {
    ServerOptions options;
    options.max_connection_age_s = 1;
    options.sources = {{.name = "bin", .directory = kCartonFrames, .fps = 10, .loop = true}};
    StartServerWith(options);
  }
};

TEST_F(ConnectionAgeTest, StreamsOutliveTheAgeAndLaterCallsReconnect) {
  v1::StreamDetectionsRequest request;
  request.set_source("bin");
  request.set_box_model("carton_s");
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
  std::unique_ptr<grpc::ClientReader<v1::DetectResponse>> reader =
      stub_->StreamDetections(&context, request);
  const auto start = std::chrono::steady_clock::now();
  int frames = 0;
  v1::DetectResponse response;
  // Well past twice the age, and a few frames (a busy machine detects
  // slower than the source plays): the stream is never cut.
  while (std::chrono::steady_clock::now() - start < std::chrono::milliseconds(2500) || frames < 4) {
    ASSERT_TRUE(reader->Read(&response)) << "stream cut after " << frames << " frames";
    ++frames;
  }
  context.TryCancel();
  while (reader->Read(&response)) {
  }
  EXPECT_EQ(reader->Finish().error_code(), grpc::StatusCode::CANCELLED);
  EXPECT_GT(frames, 3);
  // Calls after the age still succeed (on a new connection).
  grpc::Status s = DetectOn("bin", &response);
  EXPECT_TRUE(s.ok()) << s.error_message();
}

TEST(ConnectionAgeOptionTest, OutOfRangeIsInvalidArgument) {
  for (int age : {-1, 86401}) {
    ServerOptions options;
    options.listen_address = "127.0.0.1:0";
    options.max_connection_age_s = age;
    EXPECT_EQ(StartServer(options).status().code(), absl::StatusCode::kInvalidArgument) << age;
  }
}

}  // namespace
}  // namespace cornerpose::server
