#include "server/sources/directory_source.h"

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <system_error>
#include <utility>

#include "absl/strings/ascii.h"
#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "common/io/cloud_io.h"
#include "common/io/png_io.h"

namespace cornerpose::server {
namespace {

namespace fs = std::filesystem;

struct Listing {
  std::vector<std::string> files;  // *.pcd and *.png, in name order
  bool has_png = false;
};

// NAME.color.png is the colour of frame NAME, never a depth frame.
constexpr absl::string_view kColorSuffix = ".color.png";

bool IsColorImage(const fs::path& path) {
  return absl::EndsWithIgnoreCase(path.filename().string(), kColorSuffix);
}

// The colour image beside a frame: NAME.color.png for NAME.png or NAME.pcd.
fs::path ColorPathFor(const fs::path& frame) {
  fs::path color = frame;
  color.replace_extension();
  return color.string() + std::string(kColorSuffix);
}

// Attaches NAME.color.png, when there is one, to the frame's cloud as
// PointCloud::rgb (packed 0x00RRGGBB). A cloud that has colour already (a
// PCD with rgb fields) keeps it. A colour image that does not load or does
// not match the frame's size is reported and the frame plays without it:
// depth alone still detects.
void AttachColorIfBeside(const fs::path& frame, PointCloud* cloud, absl::string_view source) {
  if (cloud->has_color()) return;
  const fs::path color_path = ColorPathFor(frame);
  std::error_code error;
  if (!fs::exists(color_path, error)) return;
  if (absl::Status s = AttachColor(color_path.string(), cloud); !s.ok()) {
    std::cerr << "source " << source << ": colour not used: " << s.message() << "\n";
  }
}

absl::StatusOr<Listing> ListFrames(const std::string& directory) {
  std::error_code error;
  fs::directory_iterator it(directory, error);
  if (error) {
    return absl::NotFoundError(
        absl::StrCat("cannot read directory '", directory, "': ", error.message()));
  }
  Listing listing;
  for (const fs::directory_entry& entry : it) {
    const std::string extension = absl::AsciiStrToLower(entry.path().extension().string());
    if (extension != ".pcd" && extension != ".png") continue;
    if (IsColorImage(entry.path())) continue;
    listing.has_png |= extension == ".png";
    listing.files.push_back(entry.path().string());
  }
  if (listing.files.empty()) {
    return absl::NotFoundError(absl::StrCat("no *.pcd or *.png frames in '", directory, "'"));
  }
  std::sort(listing.files.begin(), listing.files.end());
  return listing;
}

absl::StatusOr<CameraIntrinsics> ReadIntrinsics(const std::string& directory) {
  const std::string path = (fs::path(directory) / "intrinsics.txt").string();
  std::ifstream in(path);
  if (!in) return absl::NotFoundError(absl::StrCat("cannot read '", path, "'"));
  std::stringstream text;
  text << in.rdbuf();
  const std::string stripped(absl::StripAsciiWhitespace(text.str()));
  absl::StatusOr<CameraIntrinsics> camera = ParseIntrinsics(stripped);
  if (!camera.ok()) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": ", camera.status().message()));
  }
  return camera;
}

}  // namespace

DirectorySource::DirectorySource(std::string name, std::string directory,
                                 DirectorySourceOptions options)
    : name_(std::move(name)),
      directory_(std::move(directory)),
      options_(options),
      frames_(absl::StrCat("source '", name_, "'")) {
  thread_ = std::thread([this] { Run(); });
}

DirectorySource::~DirectorySource() {
  frames_.Stop();
  thread_.join();
}

absl::StatusOr<Frame> DirectorySource::GrabNewerThan(uint64_t last_id, absl::Duration timeout) {
  return frames_.GrabNewerThan(last_id, timeout);
}

absl::StatusOr<Frame> DirectorySource::GrabAfter(uint64_t last_id, absl::Duration timeout) {
  return frames_.GrabAfter(last_id, timeout);
}

SourceStatus DirectorySource::state() const { return frames_.state(); }

void DirectorySource::Run() {
  if (!(options_.fps > 0)) {
    frames_.SetState(SourceState::kFailed, absl::StrCat("fps ", options_.fps, " must be > 0"));
    return;
  }
  absl::StatusOr<Listing> listing = ListFrames(directory_);
  if (!listing.ok()) {
    frames_.SetState(SourceState::kFailed, std::string(listing.status().message()));
    return;
  }
  // Depth images need the camera; without it every PNG is skipped (and the
  // PCDs, if any, still play), so the error is logged rather than fatal.
  LoadOptions load_options;
  load_options.color_from_beside = false;  // attached below, leniently
  if (listing->has_png) {
    absl::StatusOr<CameraIntrinsics> camera = ReadIntrinsics(directory_);
    if (camera.ok()) {
      load_options.intrinsics = *camera;
    } else {
      std::cerr << "source " << name_ << ": " << camera.status().message() << "\n";
    }
  }

  const absl::Duration period = absl::Seconds(1.0 / options_.fps);
  uint64_t next_id = 1;
  while (true) {
    bool any_loaded = false;
    std::string last_error;
    for (const std::string& path : listing->files) {
      absl::StatusOr<PointCloud> cloud = LoadPointCloud(path, load_options);
      if (!cloud.ok()) {
        // One bad recording must not take the source down: skip it.
        last_error = absl::StrCat(path, ": ", cloud.status().message());
        std::cerr << "source " << name_ << ": skipping " << last_error << "\n";
        continue;
      }
      any_loaded = true;
      Frame frame;
      frame.cloud = *std::move(cloud);
      AttachColorIfBeside(path, &frame.cloud, name_);
      if (absl::AsciiStrToLower(fs::path(path).extension().string()) == ".png") {
        frame.camera = load_options.intrinsics;
      }
      frame.id = next_id++;
      frame.capture_time = absl::Now();
      frame.source = name_;
      frame.live = false;
      frame.device_timestamp_us = static_cast<uint64_t>(
          std::llround(static_cast<double>(frame.id - 1) * 1e6 / options_.fps));
      frames_.Publish(std::move(frame));
      if (!frames_.SleepFor(period)) return;
    }
    if (!any_loaded) {
      frames_.SetState(SourceState::kFailed, absl::StrCat("no frame in '", directory_,
                                                          "' could be loaded; last: ", last_error));
      return;
    }
    if (!options_.loop) {
      frames_.SetState(SourceState::kFinished, "played every frame once");
      return;
    }
  }
}

}  // namespace cornerpose::server
