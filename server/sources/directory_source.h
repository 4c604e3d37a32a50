// Replays a directory of recorded frames as a FrameSource: the bundled
// data/frames/* and anything recorded the same way, so the service, the
// streaming path and the tests run without a camera.
#pragma once

#include <string>
#include <thread>
#include <vector>

#include "server/sources/frame_source.h"
#include "server/sources/latest_frame.h"

namespace cornerpose::server {

struct DirectorySourceOptions {
  // Frames per second the replay advances at; > 0.
  double fps = 5.0;
  // Start again from the first frame after the last; otherwise finish.
  bool loop = true;
};

// Frames are the directory's *.pcd files (LoadPointCloud) and *.png 16-bit
// depth images in millimetres, back-projected through the directory's
// intrinsics.txt ("width,height,fx,fy,cx,cy"), in file-name order. NAME.color.png
// beside NAME.png (or NAME.pcd) is that frame's colour, registered to it
// (PointCloud::rgb), and never a frame itself. A file
// that fails to load is skipped (and logged to stderr); the source keeps
// going. A directory that cannot be read, holds no frame files, or where no
// file loads puts the source in kFailed with the reason, so a misconfigured
// source never stops the server.
class DirectorySource final : public FrameSource {
 public:
  // Starts the replay thread. options.fps <= 0 fails the source.
  DirectorySource(std::string name, std::string directory, DirectorySourceOptions options = {});
  // Stops and joins the replay thread.
  ~DirectorySource() override;

  DirectorySource(const DirectorySource&) = delete;
  DirectorySource& operator=(const DirectorySource&) = delete;

  const std::string& name() const override { return name_; }
  std::string description() const override { return directory_; }
  absl::StatusOr<Frame> GrabNewerThan(uint64_t last_id, absl::Duration timeout) override;
  absl::StatusOr<Frame> GrabAfter(uint64_t last_id, absl::Duration timeout) override;
  SourceStatus state() const override;
  // Recorded frames: always a replay.
  bool live() const override { return false; }

 private:
  void Run();

  const std::string name_;
  const std::string directory_;
  const DirectorySourceOptions options_;

  LatestFrame frames_;
  std::thread thread_;
};

}  // namespace cornerpose::server
