// An OpenNI2 driver that serves a recorded-frame directory as a depth camera,
// so OpenNI2 clients (cornerpose_server's openni2 sources, NiViewer, the
// OpenNI2 recorder) run without hardware and against frames with known
// content.
//
// Device URIs:
//   cornerpose://virtual                 frames from $CORNERPOSE_VIRTUAL_CAMERA_DIR
//   cornerpose://virtual?dir=DIR&fps=N   frames from DIR (an absolute path)
//   ...&follow=1                         follow mode: DIR is being written
//                                        (the simulated cell's camera); each
//                                        frame sent is the newest PNG there
// fps defaults to $CORNERPOSE_VIRTUAL_CAMERA_FPS, else 30. When
// CORNERPOSE_VIRTUAL_CAMERA_DIR is set, "cornerpose://virtual" is also listed
// by OpenNI::enumerateDevices (so "any device" opens it); the query form is
// opened on demand. The one depth stream is DEPTH_1_MM at the frames' size,
// not mirrored, replaying the PNGs in file-name order and starting over after
// the last (follow mode: the newest PNG at each frame time, re-read only when
// a newer one appears; writers rename finished files into place), with the
// field of view from intrinsics.txt.
#include <OniCProperties.h>
#include <OniCTypes.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdlib>
#include <cstring>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "absl/status/statusor.h"
#include "absl/strings/match.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "common/io/png_io.h"
#include "tools/virtual_camera/recorded_frames.h"

// ONI_EXPORT_DRIVER uses XnLib's allocation macros, which Debian does not ship.
#define XN_NEW(type, arg) new type(arg)
#define XN_DELETE(pointer) delete (pointer)
#include <Driver/OniDriverAPI.h>

namespace cornerpose::virtual_camera {
namespace {

constexpr char kUriPrefix[] = "cornerpose://virtual";
constexpr char kDirVariable[] = "CORNERPOSE_VIRTUAL_CAMERA_DIR";
constexpr char kFpsVariable[] = "CORNERPOSE_VIRTUAL_CAMERA_FPS";
// What a Kinect v1 reports as its largest depth, millimetres.
constexpr int kNominalMaxDepthMm = 10000;

struct DeviceConfig {
  std::string directory;
  double fps = 30;
  bool follow = false;
};

std::string Env(const char* name) {
  const char* value = std::getenv(name);
  return value == nullptr ? "" : value;
}

// Parses a device URI (see the file comment). Errors name the problem.
absl::StatusOr<DeviceConfig> ParseUri(absl::string_view uri) {
  if (!absl::StartsWith(uri, kUriPrefix)) {
    return absl::InvalidArgumentError("not a cornerpose virtual camera URI");
  }
  absl::string_view query = uri.substr(sizeof(kUriPrefix) - 1);
  DeviceConfig config;
  config.directory = Env(kDirVariable);
  std::string fps_text = Env(kFpsVariable);
  if (!query.empty()) {
    if (query[0] != '?') return absl::InvalidArgumentError(absl::StrCat("bad URI '", uri, "'"));
    for (absl::string_view item : absl::StrSplit(query.substr(1), '&', absl::SkipEmpty())) {
      std::pair<std::string, std::string> kv = absl::StrSplit(item, absl::MaxSplits('=', 1));
      if (kv.first == "dir") {
        config.directory = kv.second;
      } else if (kv.first == "fps") {
        fps_text = kv.second;
      } else if (kv.first == "follow") {
        if (kv.second != "0" && kv.second != "1") {
          return absl::InvalidArgumentError(
              absl::StrCat("follow '", kv.second, "' must be 0 or 1 in '", uri, "'"));
        }
        config.follow = kv.second == "1";
      } else {
        return absl::InvalidArgumentError(absl::StrCat("unknown parameter '", kv.first, "' in '",
                                                       uri, "' (dir, fps, follow)"));
      }
    }
  }
  if (config.directory.empty()) {
    return absl::InvalidArgumentError(
        absl::StrCat("no frame directory: give ", kUriPrefix, "?dir=DIR or set ", kDirVariable));
  }
  if (!fps_text.empty() &&
      (!absl::SimpleAtod(fps_text, &config.fps) || !(config.fps > 0) || config.fps > 1000)) {
    return absl::InvalidArgumentError(absl::StrCat("fps '", fps_text, "' must be in (0, 1000]"));
  }
  return config;
}

class DepthStream final : public oni::driver::StreamBase {
 public:
  // follow_directory non-empty: follow mode (frames holds the first frame).
  DepthStream(std::shared_ptr<const RecordedFrames> frames, double fps,
              std::string follow_directory)
      : frames_(std::move(frames)), fps_(fps), follow_directory_(std::move(follow_directory)) {
    mode_.pixelFormat = ONI_PIXEL_FORMAT_DEPTH_1_MM;
    mode_.resolutionX = frames_->width;
    mode_.resolutionY = frames_->height;
    mode_.fps = static_cast<int>(fps_ + 0.5) > 0 ? static_cast<int>(fps_ + 0.5) : 1;
  }
  ~DepthStream() override { stop(); }

  OniStatus start() override {
    std::lock_guard<std::mutex> lock(mutex_);
    if (thread_.joinable()) return ONI_STATUS_OK;
    stopping_ = false;
    thread_ = std::thread([this] { Run(); });
    return ONI_STATUS_OK;
  }

  void stop() override {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stopping_ = true;
    }
    wake_.notify_all();
    if (thread_.joinable()) thread_.join();
  }

  OniBool isPropertySupported(int id) override {
    switch (id) {
      case ONI_STREAM_PROPERTY_VIDEO_MODE:
      case ONI_STREAM_PROPERTY_HORIZONTAL_FOV:
      case ONI_STREAM_PROPERTY_VERTICAL_FOV:
      case ONI_STREAM_PROPERTY_MAX_VALUE:
      case ONI_STREAM_PROPERTY_MIN_VALUE:
      case ONI_STREAM_PROPERTY_STRIDE:
      case ONI_STREAM_PROPERTY_MIRRORING:
      case ONI_STREAM_PROPERTY_CROPPING:
        return TRUE;
      default:
        return FALSE;
    }
  }

  OniStatus getProperty(int id, void* data, int* size) override {
    switch (id) {
      case ONI_STREAM_PROPERTY_VIDEO_MODE:
        return Put(mode_, data, size);
      case ONI_STREAM_PROPERTY_HORIZONTAL_FOV:
        return Put(frames_->horizontal_fov, data, size);
      case ONI_STREAM_PROPERTY_VERTICAL_FOV:
        return Put(frames_->vertical_fov, data, size);
      case ONI_STREAM_PROPERTY_MAX_VALUE:
        return Put(std::max<int>(kNominalMaxDepthMm, frames_->max_depth_mm), data, size);
      case ONI_STREAM_PROPERTY_MIN_VALUE:
        return Put(0, data, size);
      case ONI_STREAM_PROPERTY_STRIDE:
        return Put(static_cast<int>(frames_->width * sizeof(OniDepthPixel)), data, size);
      case ONI_STREAM_PROPERTY_MIRRORING:
        return Put(OniBool{FALSE}, data, size);
      case ONI_STREAM_PROPERTY_CROPPING:
        // OpenNI2's .oni player drops every frame of a stream recorded
        // without a cropping property, so report "off".
        return Put(OniCropping{FALSE, 0, 0, frames_->width, frames_->height}, data, size);
      default:
        return ONI_STATUS_NOT_SUPPORTED;
    }
  }

  // Only what is already so can be set: the recorded frames have one mode and
  // are not mirrored.
  OniStatus setProperty(int id, const void* data, int size) override {
    if (id == ONI_STREAM_PROPERTY_VIDEO_MODE && size == sizeof(OniVideoMode)) {
      const auto* mode = static_cast<const OniVideoMode*>(data);
      return mode->pixelFormat == mode_.pixelFormat && mode->resolutionX == mode_.resolutionX &&
                     mode->resolutionY == mode_.resolutionY
                 ? ONI_STATUS_OK
                 : ONI_STATUS_NOT_SUPPORTED;
    }
    if (id == ONI_STREAM_PROPERTY_MIRRORING && size == sizeof(OniBool)) {
      return *static_cast<const OniBool*>(data) ? ONI_STATUS_NOT_SUPPORTED : ONI_STATUS_OK;
    }
    if (id == ONI_STREAM_PROPERTY_CROPPING && size == sizeof(OniCropping)) {
      return static_cast<const OniCropping*>(data)->enabled ? ONI_STATUS_NOT_SUPPORTED
                                                            : ONI_STATUS_OK;
    }
    return ONI_STATUS_NOT_SUPPORTED;
  }

 private:
  template <typename T>
  static OniStatus Put(const T& value, void* data, int* size) {
    if (data == nullptr || size == nullptr || *size < static_cast<int>(sizeof(T))) {
      return ONI_STATUS_BAD_PARAMETER;
    }
    std::memcpy(data, &value, sizeof(T));
    *size = sizeof(T);
    return ONI_STATUS_OK;
  }

  // Follow mode: the newest frame in the directory, re-read when it changed;
  // a file that does not load (wrong size, removed meanwhile) keeps the last.
  const std::vector<uint16_t>& Newest() {
    const std::string path = NewestFramePath(follow_directory_);
    if (!path.empty() && path != live_path_) {
      int width = 0;
      int height = 0;
      absl::StatusOr<std::vector<uint16_t>> depth = ReadDepthPng(path, &width, &height);
      if (depth.ok() && width == frames_->width && height == frames_->height) {
        live_ = *std::move(depth);
        live_path_ = path;
      }
    }
    return live_.empty() ? frames_->depth_mm[0] : live_;
  }

  // Sends frame i % count at start + i / fps; timestamps (microseconds) are
  // i / fps exactly, so recordings replay at the set rate.
  void Run() {
    const auto start = std::chrono::steady_clock::now();
    const size_t count = frames_->depth_mm.size();
    const size_t bytes = frames_->depth_mm[0].size() * sizeof(OniDepthPixel);
    const bool follow = !follow_directory_.empty();
    for (uint64_t i = 0;; ++i) {
      const auto due = start + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                   std::chrono::duration<double>(i / fps_));
      {
        std::unique_lock<std::mutex> lock(mutex_);
        if (wake_.wait_until(lock, due, [this] { return stopping_; })) return;
      }
      OniFrame* frame = getServices().acquireFrame();
      if (frame == nullptr) continue;  // OpenNI2 out of buffers: drop this one
      if (frame->dataSize < static_cast<int>(bytes)) {
        getServices().releaseFrame(frame);
        continue;
      }
      const std::vector<uint16_t>& depth = follow ? Newest() : frames_->depth_mm[i % count];
      std::memcpy(frame->data, depth.data(), bytes);
      frame->dataSize = static_cast<int>(bytes);
      frame->sensorType = ONI_SENSOR_DEPTH;
      frame->timestamp = static_cast<uint64_t>(i * 1e6 / fps_);
      frame->frameIndex = static_cast<int>(i + 1);
      frame->width = mode_.resolutionX;
      frame->height = mode_.resolutionY;
      frame->videoMode = mode_;
      frame->croppingEnabled = FALSE;
      frame->cropOriginX = 0;
      frame->cropOriginY = 0;
      frame->stride = static_cast<int>(mode_.resolutionX * sizeof(OniDepthPixel));
      raiseNewFrame(frame);
      getServices().releaseFrame(frame);
    }
  }

  const std::shared_ptr<const RecordedFrames> frames_;
  const double fps_;
  const std::string follow_directory_;
  std::vector<uint16_t> live_;  // follow mode, the stream thread's only
  std::string live_path_;
  OniVideoMode mode_{};

  std::mutex mutex_;
  std::condition_variable wake_;
  bool stopping_ = false;  // guarded by mutex_
  std::thread thread_;
};

class Device final : public oni::driver::DeviceBase {
 public:
  Device(std::shared_ptr<const RecordedFrames> frames, double fps, std::string follow_directory)
      : frames_(std::move(frames)), fps_(fps), follow_directory_(std::move(follow_directory)) {
    mode_.pixelFormat = ONI_PIXEL_FORMAT_DEPTH_1_MM;
    mode_.resolutionX = frames_->width;
    mode_.resolutionY = frames_->height;
    mode_.fps = static_cast<int>(fps_ + 0.5) > 0 ? static_cast<int>(fps_ + 0.5) : 1;
    sensor_.sensorType = ONI_SENSOR_DEPTH;
    sensor_.numSupportedVideoModes = 1;
    sensor_.pSupportedVideoModes = &mode_;
  }

  OniStatus getSensorInfoList(OniSensorInfo** sensors, int* count) override {
    *sensors = &sensor_;
    *count = 1;
    return ONI_STATUS_OK;
  }

  oni::driver::StreamBase* createStream(OniSensorType type) override {
    if (type != ONI_SENSOR_DEPTH) return nullptr;
    return new DepthStream(frames_, fps_, follow_directory_);
  }

  void destroyStream(oni::driver::StreamBase* stream) override { delete stream; }

 private:
  const std::shared_ptr<const RecordedFrames> frames_;
  const double fps_;
  const std::string follow_directory_;
  OniVideoMode mode_{};
  OniSensorInfo sensor_{};
};

class Driver final : public oni::driver::DriverBase {
 public:
  explicit Driver(OniDriverServices* services) : DriverBase(services) {}

  OniStatus initialize(oni::driver::DeviceConnectedCallback connected,
                       oni::driver::DeviceDisconnectedCallback disconnected,
                       oni::driver::DeviceStateChangedCallback state_changed,
                       void* cookie) override {
    const OniStatus status = DriverBase::initialize(connected, disconnected, state_changed, cookie);
    if (status != ONI_STATUS_OK) return status;
    if (!Env(kDirVariable).empty()) Announce(kUriPrefix);
    return ONI_STATUS_OK;
  }

  // OpenNI2 asks every driver about a URI it does not list yet; claim ours.
  OniStatus tryDevice(const char* uri) override {
    if (uri == nullptr || !absl::StartsWith(uri, kUriPrefix)) return ONI_STATUS_ERROR;
    absl::StatusOr<DeviceConfig> config = ParseUri(uri);
    if (!config.ok()) {
      getServices().errorLoggerAppend("%s", std::string(config.status().message()).c_str());
      return ONI_STATUS_ERROR;
    }
    if (std::strlen(uri) >= ONI_MAX_STR) {
      getServices().errorLoggerAppend("URI longer than %d characters", ONI_MAX_STR - 1);
      return ONI_STATUS_ERROR;
    }
    Announce(uri);
    return ONI_STATUS_OK;
  }

  // Loads the frames now so a bad directory fails the open with the reason.
  oni::driver::DeviceBase* deviceOpen(const char* uri, const char* /*mode*/) override {
    absl::StatusOr<DeviceConfig> config = ParseUri(uri == nullptr ? "" : uri);
    if (!config.ok()) {
      getServices().errorLoggerAppend("%s", std::string(config.status().message()).c_str());
      return nullptr;
    }
    absl::StatusOr<RecordedFrames> frames = config->follow
                                                ? LoadNewestFrame(config->directory)
                                                : LoadRecordedFrames(config->directory);
    if (!frames.ok()) {
      getServices().errorLoggerAppend("cornerpose virtual camera: %s",
                                      std::string(frames.status().message()).c_str());
      return nullptr;
    }
    // A followed directory's depths grow as the scene changes: report at
    // least the nominal maximum (MAX_VALUE uses it).
    return new Device(std::make_shared<const RecordedFrames>(*std::move(frames)), config->fps,
                      config->follow ? config->directory : "");
  }

  void deviceClose(oni::driver::DeviceBase* device) override { delete device; }

  void shutdown() override {}

 private:
  // Tells OpenNI2 about a device once; it keeps the device listed after that.
  // (OpenNI2 calls tryDevice holding its own lock, which deviceConnected
  // takes again; ours is released first so the two are never nested the
  // other way round.)
  void Announce(const std::string& uri) {
    OniDeviceInfo* info = nullptr;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (announced_.count(uri) != 0) return;
      info = &announced_[uri];  // std::map: the address stays valid
    }
    std::snprintf(info->uri, sizeof(info->uri), "%s", uri.c_str());
    std::snprintf(info->vendor, sizeof(info->vendor), "cornerpose");
    std::snprintf(info->name, sizeof(info->name), "Virtual depth camera");
    info->usbVendorId = 0;
    info->usbProductId = 0;
    deviceConnected(info);
  }

  std::mutex mutex_;
  std::map<std::string, OniDeviceInfo> announced_;  // guarded by mutex_
};

}  // namespace
}  // namespace cornerpose::virtual_camera

ONI_EXPORT_DRIVER(cornerpose::virtual_camera::Driver)
