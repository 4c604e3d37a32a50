#include "tools/client/detection_outputs.h"

#include "absl/status/statusor.h"
#include "common/io/cloud_io.h"
#include "common/perception/camera_model.h"
#include "common/viz/detection_json.h"
#include "common/viz/detection_ply.h"
#include "common/viz/detection_png.h"

namespace cornerpose::tools {

absl::Status WriteDetectionOutputs(const OutputPaths& paths, const PointCloud& cloud,
                                   const std::optional<CameraIntrinsics>& camera,
                                   const Detection& detection, const BoxDims& box) {
  if (paths.json) {
    if (absl::Status s = WriteDetectionJson(*paths.json, detection, box); !s.ok()) return s;
  }
  if (paths.ply) {
    if (absl::Status s = WriteDetectionPly(*paths.ply, cloud, detection, box); !s.ok()) return s;
  }
  if (paths.png) {
    CameraIntrinsics k = camera.value_or(CameraIntrinsics{});
    if (!camera && cloud.organized()) {
      if (absl::StatusOr<CameraIntrinsics> estimated = EstimateIntrinsics(cloud); estimated.ok()) {
        k = *estimated;
      }
    }
    if (absl::Status s = WriteDetectionPng(*paths.png, cloud, k, detection, box); !s.ok()) return s;
  }
  if (paths.edges) {
    if (absl::Status s = SavePoints(*paths.edges, detection.edge_points); !s.ok()) return s;
  }
  return absl::OkStatus();
}

}  // namespace cornerpose::tools
