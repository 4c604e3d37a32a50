// The frames the virtual camera replays: every 16-bit depth PNG of a
// recorded-frame directory (data/frames/* and anything recorded the same
// way), loaded once when the device opens.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "absl/status/statusor.h"

namespace cornerpose::virtual_camera {

struct RecordedFrames {
  int width = 0;
  int height = 0;
  // Radians, from intrinsics.txt: 2 atan(width / 2 fx), 2 atan(height / 2 fy).
  // OpenNI2 describes a camera by these alone, so clients take the principal
  // point at the image centre, ((width - 1) / 2, (height - 1) / 2).
  float horizontal_fov = 0;
  float vertical_fov = 0;
  // Millimetres, row-major, width * height each; 0 = no return. In file-name
  // order.
  std::vector<std::vector<uint16_t>> depth_mm;
  // The largest depth in any frame, millimetres.
  uint16_t max_depth_mm = 0;
};

// Loads DIR/*.png (16-bit, millimetres) with DIR/intrinsics.txt
// ("width,height,fx,fy,cx,cy" or "fx,fy,cx,cy" for 640 x 480). NOT_FOUND for
// a missing directory, intrinsics file or no PNG; INVALID_ARGUMENT for a
// malformed intrinsics file or a PNG that is not 16-bit grey of the
// intrinsics' size.
absl::StatusOr<RecordedFrames> LoadRecordedFrames(const std::string& directory);

// Follow mode: a directory another program keeps writing frames into (the
// simulated cell's camera, tests/support/cell_sim), each written under a
// temporary name and renamed to NAME.png. The newest frame is the last
// *.png in name order (`*.color.png` excluded).

// The size and field of view from DIR/intrinsics.txt, and the newest frame
// (depth_mm holds exactly one). NOT_FOUND when there is no frame yet.
absl::StatusOr<RecordedFrames> LoadNewestFrame(const std::string& directory);

// The path of the newest frame, "" when there is none.
std::string NewestFramePath(const std::string& directory);

}  // namespace cornerpose::virtual_camera
