// The openni2 / oni source forms of --source (ParseSourceSpec) and of the
// configuration file (LoadServerConfig), next to the directory form, which
// must keep working unchanged.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "server/config/server_config.h"
#include "server/sources/source_spec.h"

namespace cornerpose::server {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

TEST(SourceSpecTest, DirectoryFormsAreUnchanged) {
  absl::StatusOr<SourceSpec> spec = ParseSourceSpec("bin=data/frames/carton_s:10:once");
  ASSERT_TRUE(spec.ok()) << spec.status();
  EXPECT_EQ(spec->kind, SourceKind::kDirectory);
  EXPECT_EQ(spec->directory, "data/frames/carton_s");
  EXPECT_EQ(spec->fps, 10);
  EXPECT_FALSE(spec->loop);

  spec = ParseSourceSpec("bin=/a:b/frames");
  ASSERT_TRUE(spec.ok()) << spec.status();
  EXPECT_EQ(spec->directory, "/a:b/frames");

  // A directory whose name starts like another kind.
  spec = ParseSourceSpec("x=./oni:frames:2");
  ASSERT_TRUE(spec.ok()) << spec.status();
  EXPECT_EQ(spec->kind, SourceKind::kDirectory);
  EXPECT_EQ(spec->directory, "./oni:frames");
  EXPECT_EQ(spec->fps, 2);
}

TEST(SourceSpecTest, OpenNi2DeviceTakesTheWholeUri) {
  absl::StatusOr<SourceSpec> spec = ParseSourceSpec("cam=openni2:");
  ASSERT_TRUE(spec.ok()) << spec.status();
  EXPECT_EQ(spec->name, "cam");
  EXPECT_EQ(spec->kind, SourceKind::kOpenNi2Device);
  EXPECT_EQ(spec->uri, "");

  spec = ParseSourceSpec("cam=openni2:cornerpose://virtual?dir=/x:y&fps=10");
  ASSERT_TRUE(spec.ok()) << spec.status();
  EXPECT_EQ(spec->kind, SourceKind::kOpenNi2Device);
  EXPECT_EQ(spec->uri, "cornerpose://virtual?dir=/x:y&fps=10");
}

TEST(SourceSpecTest, OniFileWithOptionalSpeedAndMode) {
  absl::StatusOr<SourceSpec> spec = ParseSourceSpec("rec=oni:/tmp/a.oni");
  ASSERT_TRUE(spec.ok()) << spec.status();
  EXPECT_EQ(spec->kind, SourceKind::kOniFile);
  EXPECT_EQ(spec->uri, "/tmp/a.oni");
  EXPECT_EQ(spec->playback_speed, 1.0);
  EXPECT_TRUE(spec->loop);

  spec = ParseSourceSpec("rec=oni:/tmp/a.oni:once");
  ASSERT_TRUE(spec.ok()) << spec.status();
  EXPECT_EQ(spec->uri, "/tmp/a.oni");
  EXPECT_FALSE(spec->loop);

  spec = ParseSourceSpec("rec=oni:/tmp/a.oni:0.5:loop");
  ASSERT_TRUE(spec.ok()) << spec.status();
  EXPECT_EQ(spec->uri, "/tmp/a.oni");
  EXPECT_EQ(spec->playback_speed, 0.5);
  EXPECT_TRUE(spec->loop);

  spec = ParseSourceSpec("rec=oni:/tmp/a.oni:2");
  ASSERT_TRUE(spec.ok()) << spec.status();
  EXPECT_EQ(spec->playback_speed, 2);
}

TEST(SourceSpecTest, BadFormsAreInvalidArgument) {
  for (const char* text : {"=openni2:", "rec=oni:", "rec=oni::once", "rec=oni:a.oni:0",
                           "rec=oni:a.oni:-1:loop", "nodir", "bin=:loop"}) {
    const absl::StatusOr<SourceSpec> spec = ParseSourceSpec(text);
    EXPECT_EQ(spec.status().code(), absl::StatusCode::kInvalidArgument) << text;
  }
}

class SourceConfigFileTest : public ::testing::Test {
 protected:
  std::string Write(const std::string& text) {
    const fs::path dir =
        fs::temp_directory_path() / ("source_config_test_" + std::to_string(getpid()));
    fs::create_directories(dir);
    const fs::path path = dir / "server.textproto";
    std::ofstream(path) << text;
    return path.string();
  }
};

TEST_F(SourceConfigFileTest, DeviceUriAndOniFileKinds) {
  const std::string path = Write(R"(
    sources { name: "any" device_uri: "" }
    sources { name: "cam" device_uri: "cornerpose://virtual" }
    sources { name: "rec" oni_file: "recordings/a.oni" loop: false playback_speed: 0.5 }
    sources { name: "bin" directory: "/frames" fps: 3 }
  )");
  absl::StatusOr<ServerOptions> options = LoadServerConfig(path);
  ASSERT_TRUE(options.ok()) << options.status();
  ASSERT_EQ(options->sources.size(), 4u);
  EXPECT_EQ(options->sources[0].kind, SourceKind::kOpenNi2Device);
  EXPECT_EQ(options->sources[0].uri, "");
  EXPECT_EQ(options->sources[1].kind, SourceKind::kOpenNi2Device);
  EXPECT_EQ(options->sources[1].uri, "cornerpose://virtual");
  EXPECT_EQ(options->sources[2].kind, SourceKind::kOniFile);
  // Relative to the file's directory.
  EXPECT_EQ(options->sources[2].uri, (fs::path(path).parent_path() / "recordings/a.oni").string());
  EXPECT_FALSE(options->sources[2].loop);
  EXPECT_EQ(options->sources[2].playback_speed, 0.5);
  EXPECT_EQ(options->sources[3].kind, SourceKind::kDirectory);
  EXPECT_EQ(options->sources[3].directory, "/frames");
  EXPECT_EQ(options->sources[3].fps, 3);
}

TEST_F(SourceConfigFileTest, BadSourcesAreInvalidArgument) {
  for (const std::string text :
       {"sources { name: \"a\" }", "sources { name: \"a\" oni_file: \"\" }",
        "sources { name: \"a\" oni_file: \"x.oni\" playback_speed: 0 }",
        "sources { name: \"a\" directory: \"x\" oni_file: \"y.oni\" }"}) {
    const absl::StatusOr<ServerOptions> options = LoadServerConfig(Write(text));
    EXPECT_EQ(options.status().code(), absl::StatusCode::kInvalidArgument) << text;
  }
  const absl::StatusOr<ServerOptions> options = LoadServerConfig(Write("sources { name: \"a\" }"));
  EXPECT_THAT(options.status().message(), HasSubstr("directory, device_uri or oni_file"));
}

}  // namespace
}  // namespace cornerpose::server
