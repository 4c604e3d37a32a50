// Carrying a detection across unchanged frames (ServerOptions::
// carry_unchanged_frames), through the real server on 127.0.0.1:0, real
// streams and real Detect calls: a recording of a pallet, five frames with
// new sensor noise, then five with its top box taken. A frame of the same
// scene gets the detection of the frame detected on; no frame after the
// take gets one from before it.
#include <grpcpp/create_channel.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "absl/strings/str_format.h"
#include "common/io/png_io.h"
#include "cornerpose/v1/perception_service.grpc.pb.h"
#include "server/server.h"
#include "tests/support/scene_generator.h"
#include "tests/support/scene_kinds.h"

namespace cornerpose::server {
namespace {

namespace fs = std::filesystem;
constexpr BoxDims kCarton{0.30, 0.20, 0.15};  // carton_s
constexpr int kPerState = 5;                  // frames before and after the take

// Writes the recording: rec_0000 .. rec_0009 and intrinsics.txt; with
// `same_scene_only` the first five only.
void WriteRecording(const fs::path& dir, bool same_scene_only = false) {
  fs::create_directories(dir);
  std::string type;
  absl::StatusOr<testing::Scene> scene =
      testing::MakeSceneOfKind("touching", kCarton, 0, 31, testing::CameraPlacement{}, &type);
  ASSERT_TRUE(scene.ok()) << scene.status();
  scene->look_seed = scene->LookSeed();
  const uint32_t noise = scene->noise_seed;
  for (int i = 0; i < (same_scene_only ? 1 : 2) * kPerState; ++i) {
    testing::Scene frame = *scene;
    frame.noise_seed = noise + i;
    if (i >= kPerState) {
      // The box whose centre is highest (a layer's boxes: any of them).
      size_t top = 0;
      for (size_t b = 1; b < frame.boxes.size(); ++b) {
        if (frame.boxes[b].world_T_box.translation().z() >
            frame.boxes[top].world_T_box.translation().z()) {
          top = b;
        }
      }
      frame.boxes.erase(frame.boxes.begin() + top);
    }
    const testing::RenderedScene r = testing::Render(frame);
    std::vector<uint16_t> depth(r.cloud.size(), 0);
    for (size_t p = 0; p < r.cloud.size(); ++p) {
      const float z = r.cloud.xyz[p].z();
      if (std::isfinite(z)) depth[p] = static_cast<uint16_t>(std::lround(z * 1000.0));
    }
    ASSERT_TRUE(WriteDepthPng((dir / absl::StrFormat("rec_%04d.png", i)).string(), depth,
                              r.camera.width, r.camera.height)
                    .ok());
    if (i == 0) {
      std::ofstream(dir / "intrinsics.txt")
          << r.camera.width << "," << r.camera.height << "," << r.camera.fx << "," << r.camera.fy
          << "," << r.camera.cx << "," << r.camera.cy << "\n";
    }
  }
}

class StreamCarryTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new fs::path(fs::temp_directory_path() /
                        ("cornerpose_carry_" + std::to_string(::getpid())));
    WriteRecording(*dir_);
    still_ = new fs::path(dir_->string() + "_still");
    WriteRecording(*still_, /*same_scene_only=*/true);
  }
  static void TearDownTestSuite() {
    fs::remove_all(*dir_);
    fs::remove_all(*still_);
    delete dir_;
    delete still_;
  }

  // A server on 127.0.0.1:0 serving `dir` as the source `name`, and a stub
  // to it; false (with a test failure) when it did not start.
  bool Start(const std::string& name, const fs::path& dir, double fps, bool loop, bool carry) {
    ServerOptions options;
    options.listen_address = "127.0.0.1:0";
    options.carry_unchanged_frames = carry;
    SourceSpec source;
    source.name = name;
    source.directory = dir.string();
    source.fps = fps;
    source.loop = loop;
    options.sources.push_back(source);
    absl::StatusOr<std::unique_ptr<RunningServer>> server = StartServer(options);
    EXPECT_TRUE(server.ok()) << server.status();
    if (!server.ok()) return false;
    server_ = *std::move(server);
    grpc::ChannelArguments args;
    args.SetMaxReceiveMessageSize(-1);
    stub_ = v1::PerceptionService::NewStub(grpc::CreateCustomChannel(
        "127.0.0.1:" + std::to_string(server_->port()), grpc::InsecureChannelCredentials(), args));
    return true;
  }

  // Streams the recording once at `fps` and returns every response by
  // frame id.
  std::map<uint64_t, v1::DetectResponse> StreamAll(bool carry, uint64_t* carried,
                                                   bool every_frame = false, double fps = 10) {
    if (!Start("rec", *dir_, fps, /*loop=*/false, carry)) return {};
    v1::StreamDetectionsRequest request;
    request.set_source("rec");
    request.set_box_model("carton_s");
    request.set_every_frame(every_frame);
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(120));
    std::unique_ptr<grpc::ClientReader<v1::DetectResponse>> reader =
        stub_->StreamDetections(&context, request);
    std::map<uint64_t, v1::DetectResponse> responses;
    v1::DetectResponse r;
    while (reader->Read(&r)) responses[r.frame_id()] = r;
    const grpc::Status end = reader->Finish();
    EXPECT_TRUE(end.ok()) << end.error_message();  // the recording played once
    *carried = server_->service().stream_frames_carried();
    return responses;
  }

  std::unique_ptr<RunningServer> server_;
  std::unique_ptr<v1::PerceptionService::Stub> stub_;

  static fs::path* dir_;
  static fs::path* still_;  // the pallet alone, five frames
};
fs::path* StreamCarryTest::dir_ = nullptr;
fs::path* StreamCarryTest::still_ = nullptr;

// Detect on a source that shows the same pallet call after call (new noise
// on every frame, the recording looping at 20 fps): the first call detects,
// the next ones carry its detection, newer frames with its boxes; with
// carry off every call detects.
TEST_F(StreamCarryTest, DetectOnASourceCarriesTheLastDetectionOfTheSameScene) {
  for (const bool carry : {true, false}) {
    SCOPED_TRACE(::testing::Message() << "carry " << carry);
    ASSERT_TRUE(Start("still", *still_, 20, /*loop=*/true, carry));
    std::vector<v1::DetectResponse> responses;
    uint64_t last_frame = 0;
    for (int call = 0; call < 4; ++call) {
      v1::DetectRequest request;
      request.set_source("still");
      request.set_box_model("carton_s");
      request.set_include_edge_points(call % 2 == 1);  // what a response carries: still carried
      grpc::ClientContext context;
      context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
      v1::DetectResponse r;
      const grpc::Status s = stub_->Detect(&context, request, &r);
      ASSERT_TRUE(s.ok()) << s.error_message();
      EXPECT_GT(r.frame_id(), last_frame) << "call " << call;
      last_frame = r.frame_id();
      responses.push_back(r);
      std::this_thread::sleep_for(std::chrono::milliseconds(120));  // a newer frame
    }
    EXPECT_EQ(responses[0].detected_frame_id(), responses[0].frame_id());
    EXPECT_GT(responses[0].boxes_size(), 0);
    for (size_t i = 1; i < responses.size(); ++i) {
      const v1::DetectResponse& r = responses[i];
      if (!carry) {
        EXPECT_EQ(r.detected_frame_id(), r.frame_id());
        continue;
      }
      EXPECT_EQ(r.detected_frame_id(), responses[0].frame_id()) << "call " << i;
      ASSERT_EQ(r.boxes_size(), responses[0].boxes_size());
      for (int b = 0; b < r.boxes_size(); ++b) {
        EXPECT_EQ(r.boxes(b).SerializeAsString(), responses[0].boxes(b).SerializeAsString());
      }
      EXPECT_EQ(r.edge_points_size() > 0, i % 2 == 1);
    }
    EXPECT_EQ(server_->service().detect_calls_carried(), carry ? 3u : 0u);
  }
}

TEST_F(StreamCarryTest, UnchangedFramesCarryTheDetectionAndATakenBoxEndsIt) {
  uint64_t carried = 0;
  const std::map<uint64_t, v1::DetectResponse> responses = StreamAll(true, &carried);
  ASSERT_GE(responses.size(), 4u);
  // Frame ids count from 1: frames 1-5 show the pallet, 6-10 it with a box
  // taken.
  constexpr uint64_t kFirstTaken = kPerState + 1;
  int carried_seen = 0;
  for (const auto& [id, r] : responses) {
    SCOPED_TRACE(::testing::Message() << "frame " << id);
    EXPECT_LE(r.detected_frame_id(), id);
    EXPECT_GE(r.detected_frame_id(), 1u);
    if (id >= kFirstTaken) {
      EXPECT_GE(r.detected_frame_id(), kFirstTaken) << "carried across the take";
    } else {
      EXPECT_LT(r.detected_frame_id(), kFirstTaken);
    }
    if (r.detected_frame_id() == id) continue;
    ++carried_seen;
    // A carried frame's boxes are those of the frame detected on.
    const auto detected = responses.find(r.detected_frame_id());
    if (detected == responses.end()) continue;
    ASSERT_EQ(r.boxes_size(), detected->second.boxes_size());
    for (int b = 0; b < r.boxes_size(); ++b) {
      EXPECT_EQ(r.boxes(b).SerializeAsString(), detected->second.boxes(b).SerializeAsString());
    }
  }
  for (const auto& [id, r] : responses) {
    std::cout << id << "<-" << r.detected_frame_id() << " (" << r.boxes_size() << " boxes) ";
  }
  std::cout << "\n";
  EXPECT_GT(carried_seen, 0);
  EXPECT_EQ(carried, static_cast<uint64_t>(carried_seen));
  // The pallet before the take and after it were each detected.
  EXPECT_GT(responses.begin()->second.boxes_size(), 0);
  EXPECT_NE(responses.begin()->second.boxes_size(), responses.rbegin()->second.boxes_size());
}

// Asked for every frame, a stream catches up on the frames that came during
// a detection (quick to carry) instead of skipping them: all ten arrive, in
// order, though each detection takes longer than a frame period at 30 fps
// (5 fps here, so that a loaded machine's slower detections stay within the
// source's kept frames too).
TEST_F(StreamCarryTest, EveryFrameArrivesWhenAskedFor) {
  uint64_t carried = 0;
  const std::map<uint64_t, v1::DetectResponse> responses =
      StreamAll(true, &carried, /*every_frame=*/true, /*fps=*/5);
  ASSERT_EQ(responses.size(), 2u * kPerState);
  EXPECT_EQ(responses.begin()->first, 1u);
  EXPECT_EQ(responses.rbegin()->first, 2u * kPerState);
  EXPECT_GE(carried, 2u * (kPerState - 2));
}

TEST_F(StreamCarryTest, WithCarryOffEveryFrameIsDetected) {
  uint64_t carried = 0;
  const std::map<uint64_t, v1::DetectResponse> responses = StreamAll(false, &carried);
  ASSERT_GE(responses.size(), 2u);
  for (const auto& [id, r] : responses) EXPECT_EQ(r.detected_frame_id(), id);
  EXPECT_EQ(carried, 0u);
}

}  // namespace
}  // namespace cornerpose::server
