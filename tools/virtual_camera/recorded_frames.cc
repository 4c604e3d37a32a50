#include "tools/virtual_camera/recorded_frames.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <system_error>

#include "absl/strings/ascii.h"
#include "absl/strings/match.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "common/io/png_io.h"

namespace cornerpose::virtual_camera {
namespace {

namespace fs = std::filesystem;

// "width,height,fx,fy,cx,cy" or "fx,fy,cx,cy" (640 x 480); the same format as
// ParseIntrinsics in common/io, which the driver does not link (it pulls in
// PCL).
absl::Status ReadIntrinsics(const std::string& directory, RecordedFrames& frames) {
  const std::string path = (fs::path(directory) / "intrinsics.txt").string();
  std::ifstream in(path);
  if (!in) return absl::NotFoundError(absl::StrCat("cannot read '", path, "'"));
  std::stringstream text;
  text << in.rdbuf();
  const std::string contents = text.str();
  std::vector<double> values;
  for (absl::string_view part : absl::StrSplit(absl::StripAsciiWhitespace(contents), ',')) {
    double value = 0;
    if (!absl::SimpleAtod(absl::StripAsciiWhitespace(part), &value) || !std::isfinite(value)) {
      return absl::InvalidArgumentError(absl::StrCat(path, ": '", part, "' is not a number"));
    }
    values.push_back(value);
  }
  if (values.size() == 4) values.insert(values.begin(), {640, 480});
  if (values.size() != 6) {
    return absl::InvalidArgumentError(
        absl::StrCat(path, ": expected width,height,fx,fy,cx,cy or fx,fy,cx,cy"));
  }
  if (values[0] < 1 || values[0] > kMaxPngSide || values[1] < 1 || values[1] > kMaxPngSide ||
      values[0] != std::floor(values[0]) || values[1] != std::floor(values[1]) ||
      !(values[2] > 0) || !(values[3] > 0)) {
    return absl::InvalidArgumentError(absl::StrCat(
        path, ": width and height must be whole and in [1, ", kMaxPngSide, "], fx and fy > 0"));
  }
  frames.width = static_cast<int>(values[0]);
  frames.height = static_cast<int>(values[1]);
  frames.horizontal_fov = static_cast<float>(2 * std::atan(frames.width / (2 * values[2])));
  frames.vertical_fov = static_cast<float>(2 * std::atan(frames.height / (2 * values[3])));
  return absl::OkStatus();
}

bool IsDepthPng(const fs::path& path) {
  const std::string name = absl::AsciiStrToLower(path.filename().string());
  return absl::EndsWith(name, ".png") && !absl::EndsWith(name, ".color.png") &&
         !absl::StartsWith(name, ".");
}

}  // namespace

std::string NewestFramePath(const std::string& directory) {
  std::error_code error;
  std::string newest;
  for (const fs::directory_entry& entry : fs::directory_iterator(directory, error)) {
    if (IsDepthPng(entry.path()) && entry.path().string() > newest) newest = entry.path().string();
  }
  return newest;
}

absl::StatusOr<RecordedFrames> LoadNewestFrame(const std::string& directory) {
  std::error_code error;
  if (!fs::is_directory(directory, error)) {
    return absl::NotFoundError(absl::StrCat("cannot read directory '", directory, "'"));
  }
  RecordedFrames frames;
  if (absl::Status s = ReadIntrinsics(directory, frames); !s.ok()) return s;
  const std::string file = NewestFramePath(directory);
  if (file.empty()) {
    return absl::NotFoundError(absl::StrCat("no *.png depth frame in '", directory, "' yet"));
  }
  int width = 0;
  int height = 0;
  absl::StatusOr<std::vector<uint16_t>> depth = ReadDepthPng(file, &width, &height);
  if (!depth.ok()) return depth.status();
  if (width != frames.width || height != frames.height) {
    return absl::InvalidArgumentError(absl::StrCat(file, " is ", width, "x", height,
                                                   ", intrinsics.txt says ", frames.width, "x",
                                                   frames.height));
  }
  frames.max_depth_mm = *std::max_element(depth->begin(), depth->end());
  frames.depth_mm.push_back(*std::move(depth));
  return frames;
}

absl::StatusOr<RecordedFrames> LoadRecordedFrames(const std::string& directory) {
  std::error_code error;
  fs::directory_iterator it(directory, error);
  if (error) {
    return absl::NotFoundError(
        absl::StrCat("cannot read directory '", directory, "': ", error.message()));
  }
  std::vector<std::string> files;
  for (const fs::directory_entry& entry : it) {
    if (IsDepthPng(entry.path())) {
      files.push_back(entry.path().string());
    }
  }
  if (files.empty()) {
    return absl::NotFoundError(absl::StrCat("no *.png depth frames in '", directory, "'"));
  }
  std::sort(files.begin(), files.end());

  RecordedFrames frames;
  if (absl::Status s = ReadIntrinsics(directory, frames); !s.ok()) return s;
  for (const std::string& file : files) {
    int width = 0;
    int height = 0;
    absl::StatusOr<std::vector<uint16_t>> depth = ReadDepthPng(file, &width, &height);
    if (!depth.ok()) return depth.status();
    if (width != frames.width || height != frames.height) {
      return absl::InvalidArgumentError(absl::StrCat(file, " is ", width, "x", height,
                                                     ", intrinsics.txt says ", frames.width, "x",
                                                     frames.height));
    }
    frames.max_depth_mm =
        std::max(frames.max_depth_mm, *std::max_element(depth->begin(), depth->end()));
    frames.depth_mm.push_back(*std::move(depth));
  }
  return frames;
}

}  // namespace cornerpose::virtual_camera
