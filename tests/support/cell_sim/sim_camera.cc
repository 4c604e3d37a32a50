#include "tests/support/cell_sim/sim_camera.h"

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <system_error>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "common/io/png_io.h"

namespace cornerpose::cell_sim {
namespace {

namespace fs = std::filesystem;

std::string FrameName(int index) { return absl::StrFormat("frame_%08d.png", index); }

}  // namespace

absl::Status SimCameraOptions::Validate() const {
  if (directory.empty()) return absl::InvalidArgumentError("SimCameraOptions.directory is empty");
  if (sensor != "kinect" && sensor != "ideal") {
    return absl::InvalidArgumentError(absl::StrCat("SimCameraOptions.sensor is '", sensor,
                                                   "', expected kinect or ideal"));
  }
  if (keep_frames < 2 || keep_frames > 1000) {
    return absl::InvalidArgumentError(
        absl::StrCat("SimCameraOptions.keep_frames is ", keep_frames, ", expected [2, 1000]"));
  }
  if (!(max_fps > 0 && max_fps <= 100)) {
    return absl::InvalidArgumentError(
        absl::StrCat("SimCameraOptions.max_fps is ", max_fps, ", expected (0, 100]"));
  }
  return absl::OkStatus();
}

absl::StatusOr<std::unique_ptr<SimCamera>> SimCamera::Start(CellWorld* world,
                                                            SimCameraOptions options) {
  if (absl::Status s = options.Validate(); !s.ok()) return s;
  std::error_code error;
  fs::create_directories(options.directory, error);
  if (error) {
    return absl::InvalidArgumentError(
        absl::StrCat("cannot create '", options.directory, "': ", error.message()));
  }
  // Frames of an earlier run would look newer or older than ours: clear them.
  for (const auto& entry : fs::directory_iterator(options.directory, error)) {
    if (entry.path().extension() == ".png" || entry.path().extension() == ".tmp") {
      fs::remove(entry.path(), error);
    }
  }
  const CameraIntrinsics& cam = world->layout().camera;
  {
    std::ofstream out(fs::path(options.directory) / "intrinsics.txt");
    out << absl::StrFormat("%d,%d,%.6f,%.6f,%.6f,%.6f\n", cam.width, cam.height, cam.fx, cam.fy,
                           cam.cx, cam.cy);
    if (!out) return absl::InternalError("cannot write intrinsics.txt");
  }
  std::unique_ptr<SimCamera> camera(new SimCamera(world, std::move(options)));
  if (absl::Status s = camera->RenderOnce(); !s.ok()) return s;
  camera->thread_ = std::thread([c = camera.get()] { c->Run(); });
  return camera;
}

SimCamera::SimCamera(CellWorld* world, SimCameraOptions options)
    : world_(world), options_(std::move(options)), next_seed_(options_.noise_seed) {}

SimCamera::~SimCamera() {
  stop_ = true;
  if (thread_.joinable()) thread_.join();
}

absl::Status SimCamera::RenderOnce() {
  const uint64_t version = world_->version();
  const auto start = std::chrono::steady_clock::now();
  const testing::Scene scene = world_->CurrentScene(next_seed_++);
  testing::NoiseOptions noise;
  noise.enabled = options_.sensor == "kinect";
  const testing::RenderedScene rendered = testing::Render(scene, noise);
  std::vector<uint16_t> depth(rendered.cloud.xyz.size(), 0);
  for (size_t i = 0; i < depth.size(); ++i) {
    const float z = rendered.cloud.xyz[i].z();
    if (std::isfinite(z) && z > 0) depth[i] = static_cast<uint16_t>(std::lround(z * 1000.0f));
  }
  last_render_ms_ = std::chrono::duration<double, std::milli>(
                        std::chrono::steady_clock::now() - start)
                        .count();
  const int index = frames_written_.load();
  const fs::path dir(options_.directory);
  const fs::path temp = dir / absl::StrCat(".", FrameName(index), ".tmp");
  if (absl::Status s = WriteDepthPng(temp.string(), depth, rendered.cloud.width,
                                     rendered.cloud.height);
      !s.ok()) {
    return s;
  }
  std::error_code error;
  fs::rename(temp, dir / FrameName(index), error);
  if (error) return absl::InternalError(absl::StrCat("rename: ", error.message()));
  if (index >= options_.keep_frames) {
    fs::remove(dir / FrameName(index - options_.keep_frames), error);
  }
  frames_written_ = index + 1;
  world_->SetRenderedVersion(version);
  return absl::OkStatus();
}

void SimCamera::Run() {
  const auto period = std::chrono::duration<double>(1.0 / options_.max_fps);
  uint64_t shown = world_->version();
  auto last = std::chrono::steady_clock::now();
  while (!stop_) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
    if (world_->version() == shown) continue;
    const auto due = last + std::chrono::duration_cast<std::chrono::steady_clock::duration>(period);
    if (std::chrono::steady_clock::now() < due) continue;
    last = std::chrono::steady_clock::now();
    shown = world_->version();
    if (absl::Status s = RenderOnce(); !s.ok()) {
      std::fprintf(stderr, "sim camera: %s\n", std::string(s.message()).c_str());
    }
  }
}

}  // namespace cornerpose::cell_sim
