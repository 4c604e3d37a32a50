// The cell's depth camera: renders the world's current state with the scene
// generator's ray caster and a sensor noise model whenever the world
// changes, and publishes each frame into a directory the way a recorded-frame
// directory holds them (16-bit millimetre PNGs plus intrinsics.txt), written
// to a temporary name and renamed, so a reader never sees half a file. The
// virtual OpenNI2 camera in follow mode (tools/virtual_camera,
// `cornerpose://virtual?follow=1`) serves the newest of them to the
// perception server.
#pragma once

#include <atomic>
#include <string>
#include <thread>

#include "absl/status/status.h"
#include "absl/time/time.h"
#include "tests/support/cell_sim/cell_world.h"

namespace cornerpose::cell_sim {

struct SimCameraOptions {
  std::string directory;  // created if missing; required
  // The sensor model: "kinect" (the generator's Kinect v1 model) or "ideal"
  // (exact depth, range limits only).
  std::string sensor = "kinect";
  // Frames kept in the directory, >= 2 (older ones are deleted).
  int keep_frames = 4;
  // At most this many renders a second, wall, (0, 100]; the world is
  // rendered only when it changed.
  double max_fps = 10.0;
  // Seed of the first frame's noise; each later frame gets the next one.
  uint32_t noise_seed = 1;

  absl::Status Validate() const;
};

class SimCamera {
 public:
  // Renders and writes the first frame before returning, so a frame source
  // opened afterwards finds one; then follows the world on its own thread.
  static absl::StatusOr<std::unique_ptr<SimCamera>> Start(CellWorld* world,
                                                          SimCameraOptions options);
  ~SimCamera();
  SimCamera(const SimCamera&) = delete;
  SimCamera& operator=(const SimCamera&) = delete;

  int frames_written() const { return frames_written_.load(); }
  // Wall milliseconds of the last render (ray cast and noise).
  double last_render_ms() const { return last_render_ms_.load(); }

 private:
  SimCamera(CellWorld* world, SimCameraOptions options);
  absl::Status RenderOnce();
  void Run();

  CellWorld* const world_;
  const SimCameraOptions options_;
  std::atomic<bool> stop_{false};
  std::atomic<int> frames_written_{0};
  std::atomic<double> last_render_ms_{0.0};
  uint32_t next_seed_;
  std::thread thread_;
};

}  // namespace cornerpose::cell_sim
