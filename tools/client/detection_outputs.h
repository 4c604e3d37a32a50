// The files a detection can be written to — JSON, coloured PLY, annotated
// PNG, edge points as PCD — shared by `client detect` and `client stream`.
#pragma once

#include <optional>
#include <string>

#include "absl/status/status.h"
#include "common/perception/types.h"

namespace cornerpose::tools {

// Where to write each output; unset = not written.
struct OutputPaths {
  std::optional<std::string> json;
  std::optional<std::string> ply;
  std::optional<std::string> png;
  std::optional<std::string> edges;

  bool any() const { return json || ply || png || edges; }
  // PLY, PNG and edge files draw the edge points.
  bool need_edge_points() const { return ply || png || edges; }
  // PLY and PNG draw over the cloud.
  bool need_cloud() const { return ply || png; }
};

// Writes every requested output. The PNG uses `camera`, else the intrinsics
// estimated from an organized cloud, else the Kinect default.
absl::Status WriteDetectionOutputs(const OutputPaths& paths, const PointCloud& cloud,
                                   const std::optional<CameraIntrinsics>& camera,
                                   const Detection& detection, const BoxDims& box);

}  // namespace cornerpose::tools
