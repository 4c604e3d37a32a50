// OpenNi2Source through OpenNI2 itself: the live-device path on the virtual
// camera, the playback path on an .oni recorded from it, and the failures
// (missing device, unreadable recording) that must be reported and retried.
#include "server/openni2_source.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <thread>

#include "tests/openni2/openni2_test_support.h"

namespace cornerpose::server {
namespace {

namespace fs = std::filesystem;
using openni2_test::CartonFrames;
using openni2_test::ExpectedClouds;
using openni2_test::MatchCloud;
using openni2_test::VirtualCameraUri;
using ::testing::HasSubstr;

// Set before OpenNI2 loads the drivers (the first source of the process), so
// "any device" finds the virtual camera.
const bool kVirtualCameraListed = [] {
  return setenv("CORNERPOSE_VIRTUAL_CAMERA_DIR", CartonFrames().c_str(), 1) == 0;
}();

// Polls `source` until `done` holds for its status or 20 s pass.
template <typename Predicate>
SourceStatus WaitForState(const FrameSource& source, Predicate done) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  SourceStatus status = source.state();
  while (!done(status) && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
    status = source.state();
  }
  return status;
}

class OpenNi2SourceTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    expected_ = new std::vector<PointCloud>(ExpectedClouds(CartonFrames(), &camera_));
    recording_ = new std::string(
        (fs::temp_directory_path() / ("openni2_source_test_" + std::to_string(getpid()) + ".oni"))
            .string());
    record_error_ = new std::string(openni2_test::RecordOni(CartonFrames(), *recording_, 12));
  }
  static void TearDownTestSuite() {
    std::error_code ignored;
    fs::remove(*recording_, ignored);
    delete expected_;
    delete recording_;
    delete record_error_;
  }

  void SetUp() override {
    ASSERT_TRUE(kVirtualCameraListed);
    ASSERT_EQ(expected_->size(), 6u) << "bundled frames missing";
  }

  // Reads `count` frames (or until the source ends), checking each against
  // the PNGs; returns the PNG index of each.
  std::vector<int> ReadFrames(FrameSource& source, int count, bool* finished = nullptr) {
    std::vector<int> matched;
    uint64_t last_id = 0;
    for (int i = 0; i < count; ++i) {
      absl::StatusOr<Frame> frame = source.GrabNewerThan(last_id, absl::Seconds(20));
      if (finished != nullptr && frame.status().code() == absl::StatusCode::kOutOfRange) {
        *finished = true;
        break;
      }
      EXPECT_TRUE(frame.ok()) << frame.status();
      if (!frame.ok()) break;
      EXPECT_GT(frame->id, last_id);
      last_id = frame->id;
      EXPECT_EQ(frame->source, source.name());
      EXPECT_EQ(frame->cloud.width, camera_.width);
      EXPECT_EQ(frame->cloud.height, camera_.height);
      // The intrinsics come back from the field of view the driver reports.
      EXPECT_TRUE(frame->camera.has_value());
      if (frame->camera) {
        EXPECT_NEAR(frame->camera->fx, camera_.fx, 1e-3);
        EXPECT_NEAR(frame->camera->fy, camera_.fy, 1e-3);
        EXPECT_NEAR(frame->camera->cx, camera_.cx, 1e-9);
        EXPECT_NEAR(frame->camera->cy, camera_.cy, 1e-9);
      }
      const int k = MatchCloud(frame->cloud, *expected_);
      EXPECT_GE(k, 0) << "frame " << frame->id << " matches no PNG within 1 mm";
      matched.push_back(k);
    }
    return matched;
  }

  static CameraIntrinsics camera_;
  static std::vector<PointCloud>* expected_;
  static std::string* recording_;
  static std::string* record_error_;
};

CameraIntrinsics OpenNi2SourceTest::camera_;
std::vector<PointCloud>* OpenNi2SourceTest::expected_ = nullptr;
std::string* OpenNi2SourceTest::recording_ = nullptr;
std::string* OpenNi2SourceTest::record_error_ = nullptr;

TEST_F(OpenNi2SourceTest, LiveVirtualCameraDeliversTheRecordedDepthAsMetricClouds) {
  const std::string uri = VirtualCameraUri(CartonFrames(), 15);
  OpenNi2Source source("cam", uri);
  EXPECT_EQ(source.description(), "openni2:" + uri);
  const std::vector<int> matched = ReadFrames(source, 8);
  ASSERT_EQ(matched.size(), 8u);
  EXPECT_GE(std::set<int>(matched.begin(), matched.end()).size(), 2u) << "replay is stuck";
  EXPECT_EQ(source.state().state, SourceState::kRunning);
}

TEST_F(OpenNi2SourceTest, AnyDeviceOpensTheListedVirtualCamera) {
  OpenNi2Source source("any", "");
  EXPECT_EQ(ReadFrames(source, 2).size(), 2u);
}

TEST_F(OpenNi2SourceTest, RecordingPlayedOnceFinishesAfterItsLastFrame) {
  ASSERT_EQ(*record_error_, "");
  OpenNi2Source source("rec", *recording_,
                       {.recording = true, .loop = false, .playback_speed = 0.5});
  EXPECT_EQ(source.description(), "oni:" + *recording_);
  bool finished = false;
  const std::vector<int> matched = ReadFrames(source, 100, &finished);
  EXPECT_TRUE(finished);
  EXPECT_GE(matched.size(), 2u);
  // Each recorded frame is delivered at most once (the recorder may have
  // written a few more than the 12 asked for when the machine is busy).
  const int recorded = openni2_test::OniDepthFrameCount(*recording_);
  ASSERT_GE(recorded, 2);
  EXPECT_LE(matched.size(), static_cast<size_t>(recorded));
  EXPECT_EQ(source.state().state, SourceState::kFinished);
  // The newest frame stays available after the end.
  EXPECT_TRUE(source.Grab(absl::Seconds(1)).ok());
}

TEST_F(OpenNi2SourceTest, RecordingPlayedInALoopGoesPastItsLength) {
  ASSERT_EQ(*record_error_, "");
  OpenNi2Source source("rec", *recording_,
                       {.recording = true, .loop = true, .playback_speed = 2.0});
  // 30 distinct frames from a recording of about 12.
  const std::vector<int> matched = ReadFrames(source, 30);
  EXPECT_EQ(matched.size(), 30u);
  EXPECT_EQ(source.state().state, SourceState::kRunning);
}

TEST_F(OpenNi2SourceTest, MissingDeviceFailsWithTheReasonAndIsRetried) {
  OpenNi2Source source(
      "gone", VirtualCameraUri("/nonexistent/frames", 10),
      {.retry_delay = absl::Milliseconds(20), .retry_max_delay = absl::Milliseconds(40)});
  const absl::StatusOr<Frame> frame = source.Grab(absl::Seconds(20));
  EXPECT_EQ(frame.status().code(), absl::StatusCode::kUnavailable);
  EXPECT_THAT(frame.status().message(), HasSubstr("/nonexistent/frames"));
  const SourceStatus retried = WaitForState(source, [](const SourceStatus& s) {
    return s.reason.find("attempt 3") != std::string::npos;
  });
  EXPECT_EQ(retried.state, SourceState::kFailed);
  EXPECT_THAT(retried.reason, HasSubstr("attempt 3"));
  EXPECT_THAT(retried.reason, HasSubstr("cannot open"));
}

TEST_F(OpenNi2SourceTest, DeviceThatAppearsLaterIsPickedUpByARetry) {
  const fs::path directory =
      fs::temp_directory_path() / ("openni2_late_" + std::to_string(getpid()));
  fs::remove_all(directory);
  OpenNi2Source source(
      "late", VirtualCameraUri(directory.string(), 10),
      {.retry_delay = absl::Milliseconds(20), .retry_max_delay = absl::Milliseconds(40)});
  EXPECT_EQ(
      WaitForState(source, [](const SourceStatus& s) { return s.state == SourceState::kFailed; })
          .state,
      SourceState::kFailed);
  // "Plug the camera in".
  fs::copy(CartonFrames(), directory);
  const SourceStatus status =
      WaitForState(source, [](const SourceStatus& s) { return s.state == SourceState::kRunning; });
  EXPECT_EQ(status.state, SourceState::kRunning) << status.reason;
  EXPECT_EQ(ReadFrames(source, 2).size(), 2u);
  fs::remove_all(directory);
}

TEST_F(OpenNi2SourceTest, DeviceThatStopsSendingIsTakenAsGoneAndReopened) {
  // One frame at once, the next only after 20 s: the source gives up on the
  // device after 300 ms, reports it and reopens it (getting a new first
  // frame).
  OpenNi2Source source("stalls", VirtualCameraUri(CartonFrames(), 0.05),
                       {.retry_delay = absl::Milliseconds(20),
                        .retry_max_delay = absl::Milliseconds(40),
                        .frame_timeout = absl::Milliseconds(300)});
  const SourceStatus gone = WaitForState(source, [](const SourceStatus& s) {
    return s.reason.find("device gone") != std::string::npos;
  });
  EXPECT_EQ(gone.state, SourceState::kFailed);
  EXPECT_THAT(gone.reason, HasSubstr("no frame for 300ms"));
  // The reopened device delivers again; ids keep increasing across reopens.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  absl::StatusOr<Frame> frame = source.GrabNewerThan(1, absl::Seconds(1));
  while (!frame.ok() && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
    frame = source.GrabNewerThan(1, absl::Seconds(1));
  }
  ASSERT_TRUE(frame.ok()) << frame.status();
  EXPECT_GE(frame->id, 2u);
  EXPECT_EQ(MatchCloud(frame->cloud, *expected_), 0);  // a new first frame
}

TEST_F(OpenNi2SourceTest, UnreadableRecordingsFailWithTheReason) {
  const fs::path garbage =
      fs::temp_directory_path() / ("openni2_garbage_" + std::to_string(getpid()) + ".oni");
  {
    std::ofstream out(garbage);
    out << "this is not an OpenNI recording\n";
  }
  OpenNi2Source bad("bad", garbage.string(), {.recording = true});
  OpenNi2Source missing("missing", "/nonexistent/recording.oni", {.recording = true});
  const SourceStatus bad_status =
      WaitForState(bad, [](const SourceStatus& s) { return s.state != SourceState::kStarting; });
  EXPECT_EQ(bad_status.state, SourceState::kFailed);
  EXPECT_THAT(bad_status.reason, HasSubstr("cannot open"));
  const SourceStatus missing_status = WaitForState(
      missing, [](const SourceStatus& s) { return s.state != SourceState::kStarting; });
  EXPECT_EQ(missing_status.state, SourceState::kFailed);
  EXPECT_THAT(missing_status.reason,
              HasSubstr("cannot read recording '/nonexistent/recording.oni'"));
  fs::remove(garbage);
}

TEST_F(OpenNi2SourceTest, NonPositivePlaybackSpeedFails) {
  OpenNi2Source source("rec", *recording_, {.recording = true, .playback_speed = 0});
  const absl::StatusOr<Frame> frame = source.Grab(absl::Seconds(20));
  EXPECT_EQ(frame.status().code(), absl::StatusCode::kUnavailable);
  EXPECT_THAT(frame.status().message(), HasSubstr("playback speed"));
}

}  // namespace
}  // namespace cornerpose::server
