// The one DetectResponse both Detect and StreamDetections send: the
// detection (common/wire), the box dimensions it used, and for a source's
// frame where it came from.
#pragma once

#include "common/perception/detector.h"
#include "cornerpose/v1/perception_service.pb.h"
#include "server/sources/frame_source.h"

namespace cornerpose::server {

// What a response carries besides the detection.
struct ResponseContents {
  bool include_edge_points = false;
  bool include_cloud = false;  // a source's frame's cloud (large), with its colour
};

// The detection, `options.box` as box_dims_used, and, when `frame` is set
// (a source's frame), its id, capture time, source and (when asked) cloud.
v1::DetectResponse MakeDetectResponse(const Detection& detection, const DetectorOptions& options,
                                      const Frame* frame, const ResponseContents& contents);

}  // namespace cornerpose::server
