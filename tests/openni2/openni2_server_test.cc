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
#include "server/sources/source_spec.h"
#include "tests/openni2/openni2_test_support.h"
#include "tests/server/source_server_fixture.h"

namespace cornerpose::server {
namespace {

namespace fs = std::filesystem;
using openni2_test::CartonFrames;
using openni2_test::VirtualCameraUri;
using ::testing::HasSubstr;

class OpenNi2ServerTest : public testing::SourceServerFixture {
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
    for (const std::string& flag :
         {"rec=oni:" + *recording_ + ":loop", "cam=openni2:" + VirtualCameraUri(CartonFrames(), 10),
          "gone=openni2:" + VirtualCameraUri("/nonexistent/frames", 10),
          std::string("lost=oni:/nonexistent/recording.oni"), "bin=" + CartonFrames()}) {
      absl::StatusOr<SourceSpec> spec = ParseSourceSpec(flag);
      ASSERT_TRUE(spec.ok()) << spec.status();
      options.sources.push_back(*spec);
    }
    StartServerWith(options);
  }

  static std::string* recording_;
  static std::string* record_error_;
};

std::string* OpenNi2ServerTest::recording_ = nullptr;
std::string* OpenNi2ServerTest::record_error_ = nullptr;

TEST_F(OpenNi2ServerTest, ListsOpenNi2SourcesWithTheirState) {
  const v1::Source rec = WaitForSource("rec");
  EXPECT_EQ(rec.description(), "oni:" + *recording_);
  EXPECT_EQ(rec.state(), v1::SOURCE_STATE_RUNNING) << rec.state_reason();
  EXPECT_FALSE(rec.live());  // an .oni recording is a replay
  const v1::Source cam = WaitForSource("cam");
  EXPECT_EQ(cam.state(), v1::SOURCE_STATE_RUNNING) << cam.state_reason();
  EXPECT_TRUE(cam.live());  // a device (the virtual camera) is live

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
    EXPECT_EQ(response.source_live(), name == "cam");
    // The device's own frame time comes through (the virtual camera's:
    // index / fps; the recording keeps what oni_record stored).
    if (name == "cam") {
      v1::DetectResponse later;
      std::this_thread::sleep_for(std::chrono::milliseconds(300));
      ASSERT_TRUE(DetectOn(name, &later).ok());
      if (later.frame_id() > response.frame_id()) {
        EXPECT_GT(later.device_timestamp_us(), response.device_timestamp_us()) << name;
      }
    }
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
  ExpectStreamInOrderUntilCancelled("rec", 3);
}

}  // namespace
}  // namespace cornerpose::server
