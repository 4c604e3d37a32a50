// PNG files through the depth reader and the colour reader (common/io/
// png_io.h), and a decoded depth image through DepthToCloud.
#include <cstddef>
#include <cstdint>

#include "common/io/cloud_io.h"
#include "common/io/png_io.h"
#include "fuzz/fuzz_input.h"

using cornerpose::fuzz::Require;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const cornerpose::fuzz::TempFile file("input.png");
  file.Write(data, size);
  int width = 0, height = 0;
  const absl::StatusOr<std::vector<uint16_t>> depth =
      cornerpose::ReadDepthPng(file.path(), &width, &height);
  if (depth.ok()) {
    Require(width > 0 && height > 0 && width <= cornerpose::kMaxPngSide &&
                height <= cornerpose::kMaxPngSide,
            "a depth image has a size in (0, kMaxPngSide]");
    Require(depth->size() == static_cast<size_t>(width) * height,
            "a depth image holds width x height pixels");
    cornerpose::CameraIntrinsics camera;
    camera.width = width;
    camera.height = height;
    camera.cx = width / 2.0;
    camera.cy = height / 2.0;
    const cornerpose::PointCloud cloud = cornerpose::DepthToCloud(*depth, camera, 0.001);
    Require(cloud.Validate().ok() && cloud.size() == depth->size(), "DepthToCloud keeps the grid");
  }
  width = height = 0;
  const absl::StatusOr<std::vector<uint8_t>> rgb =
      cornerpose::ReadRgbPng(file.path(), &width, &height);
  if (rgb.ok()) {
    Require(rgb->size() == static_cast<size_t>(width) * height * 3,
            "an RGB image holds width x height x 3 bytes");
  }
  return 0;
}
