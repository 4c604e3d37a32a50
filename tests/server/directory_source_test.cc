// DirectorySource over temporary directories of PCDs and depth PNGs, and the
// --source flag syntax. Short timeouts everywhere: a bug must fail, not hang.
#include "server/sources/directory_source.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "common/io/cloud_io.h"
#include "common/io/png_io.h"
#include "server/sources/source_spec.h"

namespace cornerpose::server {
namespace {

namespace fs = std::filesystem;

constexpr absl::Duration kWait = absl::Seconds(3);

// A fresh directory per test, removed afterwards.
class DirectorySourceTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::path(::testing::TempDir()) /
           (std::string("directory_source_") +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // An unorganized cloud of n points, so the frame is recognisable by size.
  void WritePcd(const std::string& file, int n) {
    PointCloud cloud;
    for (int i = 0; i < n; ++i) cloud.xyz.emplace_back(0.01f * i, 0.0f, 1.0f);
    cloud.width = n;
    cloud.height = 1;
    ASSERT_TRUE(SavePcd((dir_ / file).string(), cloud).ok());
  }

  // Frames 10, 20 and 30 points, written out of name order.
  void WriteThreePcds() {
    WritePcd("frame_2.pcd", 30);
    WritePcd("frame_0.pcd", 10);
    WritePcd("frame_1.pcd", 20);
  }

  // The next `count` distinct frames.
  static std::vector<Frame> Next(FrameSource& source, int count) {
    std::vector<Frame> frames;
    uint64_t last_id = 0;
    for (int i = 0; i < count; ++i) {
      absl::StatusOr<Frame> frame = source.GrabNewerThan(last_id, kWait);
      EXPECT_TRUE(frame.ok()) << frame.status();
      if (!frame.ok()) break;
      last_id = frame->id;
      frames.push_back(*std::move(frame));
    }
    return frames;
  }

  static SourceStatus WaitWhileStarting(const FrameSource& source) {
    const absl::Time give_up = absl::Now() + kWait;
    while (source.state().state == SourceState::kStarting && absl::Now() < give_up) {
      absl::SleepFor(absl::Milliseconds(5));
    }
    return source.state();
  }

  fs::path dir_;
};

// A reader a few frames behind gets every frame in order (GrabAfter); one
// whose next frame is no longer kept skips to the newest, as GrabNewerThan
// always does.
TEST_F(DirectorySourceTest, GrabAfterCatchesUpInOrderWhileFramesAreKept) {
  for (int i = 0; i < 12; ++i) WritePcd(absl::StrCat("frame_", 10 + i, ".pcd"), 10 + i);
  DirectorySource source("bin", dir_.string(), {.fps = 100, .loop = false});
  // Played once through: the last kKeptFrames are kept.
  const absl::Time give_up = absl::Now() + kWait;
  while (source.state().state != SourceState::kFinished && absl::Now() < give_up) {
    absl::SleepFor(absl::Milliseconds(5));
  }
  ASSERT_EQ(source.state().state, SourceState::kFinished);
  absl::StatusOr<Frame> newest = source.Grab(kWait);
  ASSERT_TRUE(newest.ok()) << newest.status();
  const uint64_t last = newest->id;
  ASSERT_GT(last, static_cast<uint64_t>(kKeptFrames + 2));
  // Behind by all the kept frames: each in turn.
  uint64_t id = last - kKeptFrames;
  for (int i = 0; i < kKeptFrames; ++i) {
    absl::StatusOr<Frame> next = source.GrabAfter(id, kWait);
    ASSERT_TRUE(next.ok()) << next.status();
    EXPECT_EQ(next->id, id + 1);
    EXPECT_EQ(next->cloud.size(), newest->cloud.size() - (last - next->id));
    id = next->id;
  }
  EXPECT_EQ(source.GrabAfter(id, absl::Milliseconds(50)).status().code(),
            absl::StatusCode::kOutOfRange);
  // Further behind: the newest.
  absl::StatusOr<Frame> skipped = source.GrabAfter(last - kKeptFrames - 1, kWait);
  ASSERT_TRUE(skipped.ok()) << skipped.status();
  EXPECT_EQ(skipped->id, last);
  absl::StatusOr<Frame> newer = source.GrabNewerThan(last - 3, kWait);
  ASSERT_TRUE(newer.ok()) << newer.status();
  EXPECT_EQ(newer->id, last);
}

TEST_F(DirectorySourceTest, ReplaysOnceInNameOrderThenFinishes) {
  WriteThreePcds();
  DirectorySource source("bin", dir_.string(), {.fps = 10, .loop = false});
  EXPECT_EQ(source.name(), "bin");
  EXPECT_EQ(source.description(), dir_.string());

  std::vector<Frame> frames = Next(source, 3);
  ASSERT_EQ(frames.size(), 3u);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(frames[i].cloud.size(), 10u * (i + 1)) << "frame " << i;
    EXPECT_EQ(frames[i].source, "bin");
    EXPECT_FALSE(frames[i].camera.has_value());
    if (i > 0) {
      EXPECT_GT(frames[i].id, frames[i - 1].id);
      EXPECT_GE(frames[i].capture_time, frames[i - 1].capture_time);
    }
  }

  absl::StatusOr<Frame> after = source.GrabNewerThan(frames.back().id, kWait);
  EXPECT_EQ(after.status().code(), absl::StatusCode::kOutOfRange) << after.status();
  EXPECT_EQ(source.state().state, SourceState::kFinished);
  // The last frame stays grabbable after the end.
  absl::StatusOr<Frame> last = source.Grab(absl::Milliseconds(100));
  ASSERT_TRUE(last.ok()) << last.status();
  EXPECT_EQ(last->id, frames.back().id);
}

TEST_F(DirectorySourceTest, LoopsWhenAsked) {
  WriteThreePcds();
  DirectorySource source("bin", dir_.string(), {.fps = 20, .loop = true});
  std::vector<Frame> frames = Next(source, 7);
  ASSERT_EQ(frames.size(), 7u);
  for (int i = 0; i < 7; ++i) {
    // Ids count published frames, so the size follows from the id even if
    // a busy machine made this reader miss one.
    EXPECT_EQ(frames[i].cloud.size(), 10u * ((frames[i].id - 1) % 3 + 1)) << "frame " << i;
    if (i > 0) {
      EXPECT_GT(frames[i].id, frames[i - 1].id);
    }
  }
  EXPECT_EQ(source.state().state, SourceState::kRunning);
}

TEST_F(DirectorySourceTest, SkipsAFileThatDoesNotLoad) {
  WritePcd("a.pcd", 10);
  std::ofstream(dir_ / "b.pcd") << "not a point cloud\n";
  WritePcd("c.pcd", 30);
  DirectorySource source("bin", dir_.string(), {.fps = 10, .loop = false});
  std::vector<Frame> frames = Next(source, 2);
  ASSERT_EQ(frames.size(), 2u);
  EXPECT_EQ(frames[0].cloud.size(), 10u);
  EXPECT_EQ(frames[1].cloud.size(), 30u);
}

TEST_F(DirectorySourceTest, DepthPngWithIntrinsicsIsAnOrganizedCloud) {
  // 4 x 3 at 1 m, one pixel without a return.
  std::vector<uint16_t> depth(12, 1000);
  depth[5] = 0;
  ASSERT_TRUE(WriteDepthPng((dir_ / "depth.png").string(), depth, 4, 3).ok());
  std::ofstream(dir_ / "intrinsics.txt") << "4,3,2,2,1.5,1\n";

  DirectorySource source("cam", dir_.string(), {.fps = 20, .loop = true});
  absl::StatusOr<Frame> frame = source.Grab(kWait);
  ASSERT_TRUE(frame.ok()) << frame.status();
  EXPECT_TRUE(frame->cloud.organized());
  EXPECT_EQ(frame->cloud.width, 4);
  EXPECT_EQ(frame->cloud.height, 3);
  EXPECT_NEAR(frame->cloud.xyz[0].z(), 1.0f, 1e-6);
  EXPECT_TRUE(std::isnan(frame->cloud.xyz[5].z()));
  ASSERT_TRUE(frame->camera.has_value());
  EXPECT_EQ(frame->camera->width, 4);
}

// NAME.color.png is the colour of NAME.png, never a frame of its own; a
// colour image of another size is not used (the frame plays depth-only).
TEST_F(DirectorySourceTest, ColorPngBesideADepthPngIsThatFramesColour) {
  ASSERT_TRUE(WriteDepthPng((dir_ / "a.png").string(), std::vector<uint16_t>(12, 1000), 4, 3).ok());
  ASSERT_TRUE(WriteDepthPng((dir_ / "b.png").string(), std::vector<uint16_t>(12, 1500), 4, 3).ok());
  std::ofstream(dir_ / "intrinsics.txt") << "4,3,2,2,1.5,1\n";
  std::vector<uint8_t> rgb(4 * 3 * 3, 0);
  rgb[0] = 0x12;  // pixel 0: R
  rgb[4] = 0x34;  // pixel 1: G
  ASSERT_TRUE(WriteRgbPng((dir_ / "a.color.png").string(), rgb, 4, 3).ok());
  ASSERT_TRUE(
      WriteRgbPng((dir_ / "b.color.png").string(), std::vector<uint8_t>(2 * 2 * 3), 2, 2).ok());

  DirectorySource source("rgbd", dir_.string(), {.fps = 20, .loop = false});
  std::vector<Frame> frames = Next(source, 2);
  ASSERT_EQ(frames.size(), 2u);
  // a.png (with its colour), then b.png (its colour has the wrong size).
  EXPECT_NEAR(frames[0].cloud.xyz[0].z(), 1.0f, 1e-6);
  ASSERT_TRUE(frames[0].cloud.has_color());
  EXPECT_EQ(frames[0].cloud.rgb[0], 0x00120000u);
  EXPECT_EQ(frames[0].cloud.rgb[1], 0x00003400u);
  EXPECT_NEAR(frames[1].cloud.xyz[0].z(), 1.5f, 1e-6);
  EXPECT_FALSE(frames[1].cloud.has_color());
  // Only two frames: the colour images were not played.
  absl::StatusOr<Frame> after = source.GrabNewerThan(frames.back().id, kWait);
  EXPECT_EQ(after.status().code(), absl::StatusCode::kOutOfRange) << after.status();
}

TEST_F(DirectorySourceTest, PngWithoutIntrinsicsFailsTheSourceWithAReason) {
  ASSERT_TRUE(
      WriteDepthPng((dir_ / "depth.png").string(), std::vector<uint16_t>(12, 1000), 4, 3).ok());
  DirectorySource source("cam", dir_.string(), {.fps = 20, .loop = true});
  const SourceStatus status = WaitWhileStarting(source);
  EXPECT_EQ(status.state, SourceState::kFailed);
  EXPECT_NE(status.reason.find("depth.png"), std::string::npos) << status.reason;
}

TEST_F(DirectorySourceTest, EmptyDirectoryFailsAndGrabIsUnavailable) {
  DirectorySource source("empty", dir_.string());
  const SourceStatus status = WaitWhileStarting(source);
  EXPECT_EQ(status.state, SourceState::kFailed);
  EXPECT_NE(status.reason.find("no *.pcd or *.png"), std::string::npos) << status.reason;
  absl::StatusOr<Frame> frame = source.Grab(absl::Milliseconds(100));
  EXPECT_EQ(frame.status().code(), absl::StatusCode::kUnavailable);
  EXPECT_NE(frame.status().message().find("no *.pcd or *.png"), absl::string_view::npos);
}

TEST_F(DirectorySourceTest, MissingDirectoryFailsAndGrabIsUnavailable) {
  DirectorySource source("gone", (dir_ / "missing").string());
  const SourceStatus status = WaitWhileStarting(source);
  EXPECT_EQ(status.state, SourceState::kFailed);
  EXPECT_NE(status.reason.find("cannot read directory"), std::string::npos) << status.reason;
  absl::StatusOr<Frame> frame = source.Grab(absl::Milliseconds(100));
  EXPECT_EQ(frame.status().code(), absl::StatusCode::kUnavailable);
}

TEST_F(DirectorySourceTest, DestroysPromptlyWhileRunningSlowly) {
  WriteThreePcds();
  const absl::Time start = absl::Now();
  {
    DirectorySource source("slow", dir_.string(), {.fps = 0.1, .loop = true});
    ASSERT_TRUE(source.Grab(kWait).ok());
  }
  EXPECT_LT(absl::Now() - start, absl::Seconds(2));
}

TEST(SourceSpecTest, ParsesNameDirectoryFpsAndMode) {
  absl::StatusOr<SourceSpec> spec = ParseSourceSpec("bin=data/frames/carton_s");
  ASSERT_TRUE(spec.ok()) << spec.status();
  EXPECT_EQ(spec->name, "bin");
  EXPECT_EQ(spec->directory, "data/frames/carton_s");
  EXPECT_EQ(spec->fps, 5.0);
  EXPECT_TRUE(spec->loop);

  spec = ParseSourceSpec("b=/x/y:10");
  ASSERT_TRUE(spec.ok()) << spec.status();
  EXPECT_EQ(spec->directory, "/x/y");
  EXPECT_EQ(spec->fps, 10.0);

  spec = ParseSourceSpec("b=/x:y:2.5:once");
  ASSERT_TRUE(spec.ok()) << spec.status();
  EXPECT_EQ(spec->directory, "/x:y");
  EXPECT_EQ(spec->fps, 2.5);
  EXPECT_FALSE(spec->loop);

  for (const char* bad : {"nodir", "=dir", "b=", "b=dir:0", "b=dir:-1:loop", "b=dir:loop"}) {
    EXPECT_EQ(ParseSourceSpec(bad).status().code(), absl::StatusCode::kInvalidArgument) << bad;
  }
}

}  // namespace
}  // namespace cornerpose::server
