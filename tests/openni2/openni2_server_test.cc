// The real server on 127.0.0.1:0 with OpenNI2 sources given the way the
// command line gives them (--source strings): an .oni recording and the
// virtual camera serve Detect and StreamDetections, while a missing device
// and a missing recording are listed as FAILED and the server stays up.
#include <gmock/gmock.h>
#include <grpcpp/create_channel.h>
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <memory>
#include <string>
#include <thread>

#include "cornerpose/v1/perception_service.grpc.pb.h"
#include "server/server.h"
#include "server/source_spec.h"
#include "tests/openni2/openni2_test_support.h"

namespace cornerpose::server {
namespace {

namespace fs = std::filesystem;
using openni2_test::CartonFrames;
using openni2_test::VirtualCameraUri;
using ::testing::HasSubstr;

class OpenNi2ServerTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    recording_ = new std::string(
        (fs::temp_directory_path() / ("openni2_server_test_" + std::to_string(getpid()) + ".oni"))
            .string());
    record_error_ = new std::string(openni2_test::RecordOni(CartonFrames(), *recording_, 12));
  }
  static void TearDownTestSuite() {
    std::error_code ignored;
    fs::remove(*recording_, ignored);
    delete recording_;
    delete record_error_;
  }

  void SetUp() override {
    ASSERT_EQ(*record_error_, "");
    ServerOptions options;
    options.listen_address = "127.0.0.1:0";
    for (const std::string& flag :
         {"rec=oni:" + *recording_ + ":loop", "cam=openni2:" + VirtualCameraUri(CartonFrames(), 10),
          "gone=openni2:" + VirtualCameraUri("/nonexistent/frames", 10),
          std::string("lost=oni:/nonexistent/recording.oni"), "bin=" + CartonFrames()}) {
      absl::StatusOr<SourceSpec> spec = ParseSourceSpec(flag);
      ASSERT_TRUE(spec.ok()) << spec.status();
      options.sources.push_back(*spec);
    }
    absl::StatusOr<std::unique_ptr<RunningServer>> server = StartServer(options);
    ASSERT_TRUE(server.ok()) << server.status();
    server_ = *std::move(server);
    grpc::ChannelArguments args;
    args.SetMaxReceiveMessageSize(-1);
    stub_ = v1::PerceptionService::NewStub(grpc::CreateCustomChannel(
        "127.0.0.1:" + std::to_string(server_->port()), grpc::InsecureChannelCredentials(), args));
  }

  v1::ListSourcesResponse ListSources() {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
    v1::ListSourcesResponse response;
    grpc::Status s = stub_->ListSources(&context, v1::ListSourcesRequest(), &response);
    EXPECT_TRUE(s.ok()) << s.error_message();
    return response;
  }

  // Polls ListSources until `name` leaves STARTING (or 20 s pass).
  v1::Source WaitForSource(const std::string& name) {
    v1::Source found;
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
    while (std::chrono::steady_clock::now() < deadline) {
      const v1::ListSourcesResponse listed = ListSources();
      for (const v1::Source& source : listed.sources()) {
        if (source.name() == name) found = source;
      }
      if (found.state() != v1::SOURCE_STATE_STARTING &&
          found.state() != v1::SOURCE_STATE_UNSPECIFIED) {
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return found;
  }

  grpc::Status DetectOn(const std::string& source, v1::DetectResponse* response) {
    v1::DetectRequest request;
    request.set_source(source);
    request.set_box_model("carton_s");
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
    return stub_->Detect(&context, request, response);
  }

  static std::string* recording_;
  static std::string* record_error_;
  std::unique_ptr<RunningServer> server_;
  std::unique_ptr<v1::PerceptionService::Stub> stub_;
};

std::string* OpenNi2ServerTest::recording_ = nullptr;
std::string* OpenNi2ServerTest::record_error_ = nullptr;

TEST_F(OpenNi2ServerTest, ListsOpenNi2SourcesWithTheirState) {
  const v1::Source rec = WaitForSource("rec");
  EXPECT_EQ(rec.description(), "oni:" + *recording_);
  EXPECT_EQ(rec.state(), v1::SOURCE_STATE_RUNNING) << rec.state_reason();
  const v1::Source cam = WaitForSource("cam");
  EXPECT_EQ(cam.state(), v1::SOURCE_STATE_RUNNING) << cam.state_reason();

  const v1::Source gone = WaitForSource("gone");
  EXPECT_EQ(gone.state(), v1::SOURCE_STATE_FAILED);
  EXPECT_THAT(gone.state_reason(), HasSubstr("/nonexistent/frames"));
  EXPECT_THAT(gone.state_reason(), HasSubstr("retrying"));
  const v1::Source lost = WaitForSource("lost");
  EXPECT_EQ(lost.state(), v1::SOURCE_STATE_FAILED);
  EXPECT_THAT(lost.state_reason(), HasSubstr("/nonexistent/recording.oni"));
  EXPECT_EQ(ListSources().sources_size(), 5);
}

TEST_F(OpenNi2ServerTest, DetectOnOpenNi2SourcesFindsBoxesAndFailedOnesAreUnavailable) {
  for (const std::string name : {"rec", "cam"}) {
    v1::DetectResponse response;
    grpc::Status s = DetectOn(name, &response);
    ASSERT_TRUE(s.ok()) << name << ": " << s.error_message();
    EXPECT_EQ(response.source(), name);
    EXPECT_GT(response.frame_id(), 0u);
    EXPECT_GT(response.boxes_size(), 0) << name;
  }
  WaitForSource("gone");
  v1::DetectResponse response;
  grpc::Status s = DetectOn("gone", &response);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::UNAVAILABLE);
  EXPECT_THAT(s.error_message(), HasSubstr("/nonexistent/frames"));

  // Still serving, from OpenNI2 and from the directory.
  for (const std::string name : {"rec", "bin"}) {
    s = DetectOn(name, &response);
    EXPECT_TRUE(s.ok()) << name << ": " << s.error_message();
  }
}

TEST_F(OpenNi2ServerTest, StreamFromARecordingDeliversNewFramesUntilCancelled) {
  v1::StreamDetectionsRequest request;
  request.set_source("rec");
  request.set_box_model("carton_s");
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
  std::unique_ptr<grpc::ClientReader<v1::DetectResponse>> reader =
      stub_->StreamDetections(&context, request);
  uint64_t last_id = 0;
  for (int i = 0; i < 3; ++i) {
    v1::DetectResponse response;
    ASSERT_TRUE(reader->Read(&response)) << "frame " << i;
    EXPECT_GT(response.frame_id(), last_id);
    last_id = response.frame_id();
    EXPECT_EQ(response.source(), "rec");
    EXPECT_GT(response.boxes_size(), 0);
  }
  context.TryCancel();
  v1::DetectResponse ignored;
  while (reader->Read(&ignored)) {
  }
  EXPECT_EQ(reader->Finish().error_code(), grpc::StatusCode::CANCELLED);
}

}  // namespace
}  // namespace cornerpose::server
