#include "tests/openni2/openni2_test_support.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <OpenNI.h>

#include "absl/strings/ascii.h"
#include "absl/strings/str_cat.h"
#include "common/io/cloud_io.h"

namespace cornerpose::openni2_test {

namespace fs = std::filesystem;

std::string CartonFrames() { return std::string(CORNERPOSE_SOURCE_DIR) + "/data/frames/carton_s"; }

std::string VirtualCameraUri(const std::string& directory, double fps) {
  return absl::StrCat("cornerpose://virtual?dir=", directory, "&fps=", fps);
}

std::vector<PointCloud> ExpectedClouds(const std::string& directory, CameraIntrinsics* camera) {
  std::ifstream in(fs::path(directory) / "intrinsics.txt");
  std::stringstream text;
  text << in.rdbuf();
  const std::string contents = text.str();
  const absl::string_view stripped = absl::StripAsciiWhitespace(contents);
  absl::StatusOr<CameraIntrinsics> parsed =
      ParseIntrinsics(std::string_view(stripped.data(), stripped.size()));
  if (!parsed.ok()) return {};
  *camera = *parsed;
  std::vector<std::string> files;
  for (const fs::directory_entry& entry : fs::directory_iterator(directory)) {
    if (entry.path().extension() == ".png") files.push_back(entry.path().string());
  }
  std::sort(files.begin(), files.end());
  std::vector<PointCloud> clouds;
  for (const std::string& file : files) {
    int width = 0;
    int height = 0;
    absl::StatusOr<std::vector<uint16_t>> depth = ReadDepthPng(file, &width, &height);
    if (!depth.ok()) return {};
    clouds.push_back(DepthToCloud(*depth, *camera, 0.001));
  }
  return clouds;
}

int MatchCloud(const PointCloud& cloud, const std::vector<PointCloud>& expected, float tolerance) {
  for (size_t k = 0; k < expected.size(); ++k) {
    const PointCloud& want = expected[k];
    if (want.width != cloud.width || want.height != cloud.height) continue;
    bool same = true;
    for (size_t i = 0; i < want.xyz.size() && same; ++i) {
      const Eigen::Vector3f& a = want.xyz[i];
      const Eigen::Vector3f& b = cloud.xyz[i];
      if (std::isnan(a.z()) || std::isnan(b.z())) {
        same = std::isnan(a.z()) && std::isnan(b.z());
      } else {
        same = (a - b).cwiseAbs().maxCoeff() <= tolerance;
      }
    }
    if (same) return static_cast<int>(k);
  }
  return -1;
}

std::string RecordOni(const std::string& directory, const std::string& out, int frames) {
  const std::string command =
      absl::StrCat("timeout 60 '", ONI_RECORD_PATH, "' --uri '", VirtualCameraUri(directory, 30),
                   "' --out '", out, "' --frames ", frames, " --timeout_s 30");
  const int status = std::system(command.c_str());
  if (status != 0) return absl::StrCat("'", command, "' exited with ", status);
  std::error_code error;
  if (fs::file_size(out, error) == 0 || error) return absl::StrCat(out, " is missing or empty");
  return "";
}

int OniDepthFrameCount(const std::string& path) {
  if (openni::OpenNI::initialize() != openni::STATUS_OK) return -1;
  openni::Device device;
  if (device.open(path.c_str()) != openni::STATUS_OK) return -1;
  int count = -1;
  openni::VideoStream depth;
  if (depth.create(device, openni::SENSOR_DEPTH) == openni::STATUS_OK) {
    if (openni::PlaybackControl* playback = device.getPlaybackControl(); playback != nullptr) {
      count = playback->getNumberOfFrames(depth);
    }
    depth.destroy();
  }
  device.close();
  return count;
}

}  // namespace cornerpose::openni2_test
