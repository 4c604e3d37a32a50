// Records the depth stream of any OpenNI2 device to an .oni file with
// OpenNI2's own recorder:
//   oni_record --uri URI --out FILE.oni --frames N [--timeout_s S]
// --uri "" opens any device; "cornerpose://virtual?dir=DIR" the virtual
// camera (tools/virtual_camera). The recorder starts asynchronously, so the
// file holds about N frames (one or two at the start may be missed). Exit
// status 0 on success, 1 with a message on stderr otherwise; never waits
// longer than --timeout_s for frames.
#include <OpenNI.h>

#include <chrono>
#include <cstdio>
#include <string>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/flags/usage.h"

ABSL_FLAG(std::string, uri, "", "the OpenNI2 device URI; empty = any device");
ABSL_FLAG(std::string, out, "", "the .oni file to write");
ABSL_FLAG(int, frames, 30, "depth frames to record; > 0");
ABSL_FLAG(double, timeout_s, 30, "give up when the frames have not come within this many seconds");

namespace {

int Fail(const char* what) {
  std::fprintf(stderr, "oni_record: %s: %s\n", what, openni::OpenNI::getExtendedError());
  return 1;
}

int Record() {
  const std::string uri = absl::GetFlag(FLAGS_uri);
  const std::string out = absl::GetFlag(FLAGS_out);
  const int frames = absl::GetFlag(FLAGS_frames);
  if (out.empty() || frames <= 0) {
    std::fprintf(stderr, "oni_record: --out is required and --frames must be > 0\n");
    return 1;
  }
  openni::Device device;
  if (device.open(uri.empty() ? openni::ANY_DEVICE : uri.c_str()) != openni::STATUS_OK) {
    return Fail(("cannot open device '" + uri + "'").c_str());
  }
  openni::VideoStream depth;
  if (depth.create(device, openni::SENSOR_DEPTH) != openni::STATUS_OK) {
    return Fail("the device has no depth stream");
  }
  if (depth.start() != openni::STATUS_OK) return Fail("cannot start the depth stream");
  openni::Recorder recorder;
  if (recorder.create(out.c_str()) != openni::STATUS_OK) {
    return Fail(("cannot write '" + out + "'").c_str());
  }
  if (recorder.attach(depth) != openni::STATUS_OK || recorder.start() != openni::STATUS_OK) {
    return Fail("cannot start recording");
  }

  const auto deadline = std::chrono::steady_clock::now() +
                        std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                            std::chrono::duration<double>(absl::GetFlag(FLAGS_timeout_s)));
  int read = 0;
  while (read < frames) {
    if (std::chrono::steady_clock::now() > deadline) {
      std::fprintf(stderr, "oni_record: only %d of %d frames within the timeout\n", read, frames);
      return 1;
    }
    openni::VideoStream* streams[] = {&depth};
    int ready = -1;
    if (openni::OpenNI::waitForAnyStream(streams, 1, &ready, 500) != openni::STATUS_OK) continue;
    openni::VideoFrameRef frame;
    if (depth.readFrame(&frame) == openni::STATUS_OK) ++read;
  }
  // Closing the recorder writes the frame count and seek table.
  recorder.stop();
  recorder.destroy();
  depth.stop();
  depth.destroy();
  device.close();
  std::printf("recorded %d depth frames to %s\n", read, out.c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  absl::SetProgramUsageMessage(
      "records an OpenNI2 device's depth stream: oni_record --uri URI --out FILE.oni --frames N");
  absl::ParseCommandLine(argc, argv);
  if (openni::OpenNI::initialize() != openni::STATUS_OK) return Fail("cannot initialize OpenNI2");
  const int status = Record();
  openni::OpenNI::shutdown();
  return status;
}
