#include "server/sources/openni2_source.h"

#include <OpenNI.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iostream>
#include <tuple>
#include <utility>
#include <vector>

#include "absl/strings/str_cat.h"
#include "common/io/cloud_io.h"
#include "server/sources/openni2_init.h"

namespace cornerpose::server {
namespace {

// How long one wait for a frame lasts, so a stop request is seen promptly.
constexpr int kPollMilliseconds = 100;

std::string OpenNiError() {
  std::string error = openni::OpenNI::getExtendedError();
  while (!error.empty() && (error.back() == '\n' || error.back() == ' ')) error.pop_back();
  while (!error.empty() && (error.front() == '\n' || error.front() == '\t')) error.erase(0, 1);
  return error.empty() ? "no reason given" : error;
}

bool IsMetricDepth(openni::PixelFormat format) {
  return format == openni::PIXEL_FORMAT_DEPTH_1_MM || format == openni::PIXEL_FORMAT_DEPTH_100_UM;
}

// Live devices may start in a shift or colour-registered mode: pick a metric
// depth mode, the largest, preferring millimetres. Recordings keep theirs.
void ChooseDepthMode(openni::VideoStream& depth) {
  if (IsMetricDepth(depth.getVideoMode().getPixelFormat())) return;
  const openni::Array<openni::VideoMode>& modes = depth.getSensorInfo().getSupportedVideoModes();
  int best = -1;
  for (int i = 0; i < modes.getSize(); ++i) {
    if (!IsMetricDepth(modes[i].getPixelFormat())) continue;
    const auto key = [](const openni::VideoMode& m) {
      return std::make_tuple(m.getResolutionX() * m.getResolutionY(),
                             m.getPixelFormat() == openni::PIXEL_FORMAT_DEPTH_1_MM, m.getFps());
    };
    if (best < 0 || key(modes[i]) > key(modes[best])) best = i;
  }
  if (best >= 0) depth.setVideoMode(modes[best]);
}

// The depth image as an organized metric cloud with the intrinsics OpenNI2
// implies (see the class comment).
absl::StatusOr<Frame> ToFrame(const openni::VideoFrameRef& ref, float hfov, float vfov,
                              bool mirrored) {
  const openni::VideoMode mode = ref.getVideoMode();
  double scale = 0;
  if (mode.getPixelFormat() == openni::PIXEL_FORMAT_DEPTH_1_MM) {
    scale = 0.001;
  } else if (mode.getPixelFormat() == openni::PIXEL_FORMAT_DEPTH_100_UM) {
    scale = 0.0001;
  } else {
    return absl::FailedPreconditionError(absl::StrCat("depth frames in pixel format ",
                                                      mode.getPixelFormat(),
                                                      ", not DEPTH_1_MM or DEPTH_100_UM"));
  }
  const int width = ref.getWidth();
  const int height = ref.getHeight();
  const int stride = ref.getStrideInBytes();
  if (width <= 0 || height <= 0 || ref.getData() == nullptr ||
      stride < width * static_cast<int>(sizeof(uint16_t)) || ref.getDataSize() < stride * height) {
    return absl::DataLossError(absl::StrCat("malformed depth frame ", width, "x", height,
                                            ", stride ", stride, ", ", ref.getDataSize(),
                                            " bytes"));
  }
  // The field of view spans the full (uncropped) image.
  const int full_width = ref.getCroppingEnabled() ? mode.getResolutionX() : width;
  const int full_height = ref.getCroppingEnabled() ? mode.getResolutionY() : height;
  CameraIntrinsics camera;
  camera.width = width;
  camera.height = height;
  camera.fx = full_width / (2.0 * std::tan(hfov / 2.0));
  camera.fy = full_height / (2.0 * std::tan(vfov / 2.0));
  camera.cx = (full_width - 1) / 2.0 - (ref.getCroppingEnabled() ? ref.getCropOriginX() : 0);
  camera.cy = (full_height - 1) / 2.0 - (ref.getCroppingEnabled() ? ref.getCropOriginY() : 0);
  if (absl::Status valid = camera.Validate(); !valid.ok()) {
    return absl::FailedPreconditionError(
        absl::StrCat("intrinsics from the device's field of view (", hfov, ", ", vfov,
                     " rad): ", valid.message()));
  }

  std::vector<uint16_t> depth(static_cast<size_t>(width) * height);
  const auto* bytes = static_cast<const uint8_t*>(ref.getData());
  for (int v = 0; v < height; ++v) {
    std::memcpy(&depth[static_cast<size_t>(v) * width], bytes + static_cast<size_t>(v) * stride,
                width * sizeof(uint16_t));
    // A mirrored image is flipped left-right; undo it so x points right.
    if (mirrored) {
      std::reverse(depth.begin() + static_cast<ptrdiff_t>(v) * width,
                   depth.begin() + static_cast<ptrdiff_t>(v + 1) * width);
    }
  }
  Frame frame;
  frame.cloud = DepthToCloud(depth, camera, scale);
  frame.camera = camera;
  return frame;
}

}  // namespace

OpenNi2Source::OpenNi2Source(std::string name, std::string uri, OpenNi2SourceOptions options)
    : name_(std::move(name)),
      uri_(std::move(uri)),
      options_(options),
      frames_(absl::StrCat("source '", name_, "' (", description(), ")")) {
  thread_ = std::thread([this] { Run(); });
}

OpenNi2Source::~OpenNi2Source() {
  frames_.Stop();
  thread_.join();
}

std::string OpenNi2Source::description() const {
  return options_.recording ? absl::StrCat("oni:", uri_) : absl::StrCat("openni2:", uri_);
}

absl::StatusOr<Frame> OpenNi2Source::GrabNewerThan(uint64_t last_id, absl::Duration timeout) {
  return frames_.GrabNewerThan(last_id, timeout);
}

absl::StatusOr<Frame> OpenNi2Source::GrabAfter(uint64_t last_id, absl::Duration timeout) {
  return frames_.GrabAfter(last_id, timeout);
}

SourceStatus OpenNi2Source::state() const { return frames_.state(); }

void OpenNi2Source::Publish(Frame frame) {
  frame.id = next_id_++;
  frame.capture_time = absl::Now();
  frame.source = name_;
  frame.live = live();
  frames_.Publish(std::move(frame));
  delivered_ = true;
}

void OpenNi2Source::Run() {
  if (options_.recording &&
      !(options_.playback_speed > 0 && std::isfinite(options_.playback_speed))) {
    frames_.SetState(SourceState::kFailed,
                     absl::StrCat("playback speed ", options_.playback_speed, " must be > 0"));
    return;
  }
  absl::Duration delay = options_.retry_delay;
  for (int attempt = 1;; ++attempt) {
    std::string reason;
    delivered_ = false;
    const SessionEnd end = Capture(&reason);
    if (end == SessionEnd::kStopping) return;
    if (end == SessionEnd::kFinished) {
      frames_.SetState(SourceState::kFinished, "played the recording once");
      return;
    }
    if (delivered_) delay = options_.retry_delay;
    reason = absl::StrCat(reason, " (attempt ", attempt, "; retrying in ",
                          absl::FormatDuration(delay), ")");
    std::cerr << "source " << name_ << ": " << reason << "\n";
    frames_.SetState(SourceState::kFailed, std::move(reason));
    if (!frames_.SleepFor(delay)) return;
    delay = std::min(delay * 2, std::max(options_.retry_max_delay, options_.retry_delay));
  }
}

OpenNi2Source::SessionEnd OpenNi2Source::Capture(std::string* reason) {
  if (absl::Status s = EnsureOpenNi2Initialized(); !s.ok()) {
    *reason = std::string(s.message());
    return SessionEnd::kFailed;
  }
  if (options_.recording) {
    // OpenNI2 only says "couldn't open device"; say why when we can.
    std::ifstream probe(uri_, std::ios::binary);
    if (!probe) {
      *reason = absl::StrCat("cannot read recording '", uri_, "': ", std::strerror(errno));
      return SessionEnd::kFailed;
    }
  }
  // Declared before the stream so that the stream is destroyed first.
  openni::Device device;
  if (device.open(uri_.empty() ? openni::ANY_DEVICE : uri_.c_str()) != openni::STATUS_OK) {
    *reason = absl::StrCat("cannot open ", uri_.empty() ? "any OpenNI2 device" : "'" + uri_ + "'",
                           ": ", OpenNiError());
    return SessionEnd::kFailed;
  }
  const bool file = device.isFile();
  openni::PlaybackControl* playback = file ? device.getPlaybackControl() : nullptr;
  if (playback != nullptr) {
    playback->setRepeatEnabled(options_.loop);
    playback->setSpeed(static_cast<float>(options_.playback_speed));
  }
  if (!device.hasSensor(openni::SENSOR_DEPTH)) {
    *reason = absl::StrCat("'", uri_, "' has no depth stream");
    return SessionEnd::kFailed;
  }
  openni::VideoStream depth;
  if (depth.create(device, openni::SENSOR_DEPTH) != openni::STATUS_OK) {
    *reason = absl::StrCat("cannot create the depth stream: ", OpenNiError());
    return SessionEnd::kFailed;
  }
  if (!file) {
    ChooseDepthMode(depth);
    depth.setMirroringEnabled(false);  // not every device can; handled below
  }
  if (depth.start() != openni::STATUS_OK) {
    *reason = absl::StrCat("cannot start the depth stream: ", OpenNiError());
    return SessionEnd::kFailed;
  }
  // Torn down in order on every way out: a recording's player first held
  // in manual mode (no more frames pushed), then the stream stopped and
  // destroyed, then the device closed. Left to the destructors, OpenNI2's
  // file player thread could still push a frame into the stream being
  // destroyed and crash (seen at the end of a recording played once, one
  // run in seven on a loaded machine).
  struct Teardown {
    openni::Device& device;
    openni::VideoStream& stream;
    openni::PlaybackControl* playback;
    ~Teardown() {
      if (playback != nullptr) playback->setSpeed(-1.0f);
      stream.stop();
      stream.destroy();
      device.close();
    }
  } teardown{device, depth, playback};
  const float hfov = depth.getHorizontalFieldOfView();
  const float vfov = depth.getVerticalFieldOfView();
  const bool mirrored = depth.getMirroringEnabled();
  // Recordings played once end after their last frame (frame indices run
  // 1..count); the frame timeout is the fallback when the count is unknown.
  const int frame_count = playback != nullptr ? playback->getNumberOfFrames(depth) : 0;
  const bool play_once = file && !options_.loop;
  // A recording played once whose length is known is played by OpenNI2 in
  // a loop all the same, and the session ends at its last frame (or the
  // first frame of the next pass, when the last was skipped): once OpenNI2's
  // file player reaches the end of a recording it does not repeat, its
  // thread idles walking its list of streams unlocked, and tearing the
  // stream down under it crashed the process (libOniFile, one run in about
  // 30 on a loaded machine). Playing on, it waits in manual mode at
  // teardown, as for a recording played in a loop.
  if (play_once && frame_count > 0) playback->setRepeatEnabled(true);
  int last_index = 0;

  absl::Time last_frame = absl::Now();
  bool any_frame = false;
  while (!frames_.stopping()) {
    openni::VideoStream* streams[] = {&depth};
    int ready = -1;
    if (openni::OpenNI::waitForAnyStream(streams, 1, &ready, kPollMilliseconds) !=
        openni::STATUS_OK) {
      if (absl::Now() - last_frame < options_.frame_timeout) continue;
      if (play_once && any_frame) return SessionEnd::kFinished;
      *reason = absl::StrCat("no frame for ", absl::FormatDuration(options_.frame_timeout),
                             any_frame ? " (device gone?)" : "");
      return SessionEnd::kFailed;
    }
    openni::VideoFrameRef ref;
    if (depth.readFrame(&ref) != openni::STATUS_OK || !ref.isValid()) continue;
    last_frame = absl::Now();
    any_frame = true;
    absl::StatusOr<Frame> frame = ToFrame(ref, hfov, vfov, mirrored);
    if (!frame.ok()) {
      *reason = std::string(frame.status().message());
      return SessionEnd::kFailed;
    }
    // The next pass began (the last frame was skipped): the recording is
    // over, and this frame was already delivered in the first pass.
    const int index = ref.getFrameIndex();
    if (play_once && frame_count > 0 && index < last_index) return SessionEnd::kFinished;
    last_index = index;
    frame->device_timestamp_us = ref.getTimestamp();
    Publish(*std::move(frame));
    if (play_once && frame_count > 0 && index >= frame_count) return SessionEnd::kFinished;
  }
  return SessionEnd::kStopping;
}

}  // namespace cornerpose::server
