// A frame as the web view fetches it: an 8-bit PNG (the colour image, or
// the depth shaded) and the compact cloud "CPC1" (web/README.md).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "server/sources/frame_source.h"

namespace cornerpose::server {

// The camera the image is drawn for: the frame's, else `detector_camera`,
// else the default intrinsics sized to an organized cloud.
CameraIntrinsics FrameImageCamera(const Frame& frame,
                                  const std::optional<CameraIntrinsics>& detector_camera);

// The points the view's cloud holds: every 4th pixel of every 4th row of an
// organized cloud (every 16th point of an unorganized one), valid only.
std::vector<size_t> ViewCloudIndices(const PointCloud& cloud);

// The frame as a PNG of camera.width x camera.height: the colour where the
// cloud has it, else the depth shaded (near bright, no return black).
std::string FramePng(const Frame& frame, const CameraIntrinsics& camera);

// "CPC1", uint32 count, uint32 flags (bit 0: rgb), float32 xyz..., [uint8 rgb...].
std::string FrameCloudBin(const Frame& frame);

}  // namespace cornerpose::server
