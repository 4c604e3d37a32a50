#include "server/service/detect_response.h"

#include "common/wire/box_wire.h"
#include "common/wire/cloud_wire.h"
#include "common/wire/detection_wire.h"

namespace cornerpose::server {

v1::DetectResponse MakeDetectResponse(const Detection& detection, const DetectorOptions& options,
                                      const Frame* frame, const ResponseContents& contents) {
  v1::DetectResponse response = wire::DetectionToProto(detection, contents.include_edge_points);
  *response.mutable_box_dims_used() = wire::ToProto(options.box);
  if (frame == nullptr) return response;
  response.set_frame_id(frame->id);
  response.set_detected_frame_id(frame->id);
  response.set_capture_time_unix_nanos(absl::ToUnixNanos(frame->capture_time));
  response.set_source(frame->source);
  response.set_source_live(frame->live);
  response.set_device_timestamp_us(frame->device_timestamp_us);
  if (contents.include_cloud) *response.mutable_cloud() = wire::CloudToProto(frame->cloud);
  return response;
}

}  // namespace cornerpose::server
