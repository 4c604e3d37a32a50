#include "common/wire/detection_wire.h"

#include <utility>

#include "common/wire/box_wire.h"
#include "common/wire/geometry_wire.h"

namespace cornerpose::wire {

v1::DetectResponse DetectionToProto(const Detection& detection, bool include_edge_points) {
  v1::DetectResponse out;
  for (const DetectedBox& box : detection.boxes) *out.add_boxes() = ToProto(box);
  for (const EdgeSegment& segment : detection.segments) {
    v1::EdgeSegment* s = out.add_segments();
    *s->mutable_end1() = ToProto(segment.end1);
    *s->mutable_end2() = ToProto(segment.end2);
    s->set_num_points(static_cast<uint32_t>(segment.num_points));
  }
  for (const Corner& corner : detection.corners) {
    *out.add_corners()->mutable_position() = ToProto(corner.position);
  }
  if (include_edge_points) {
    out.mutable_edge_points()->Reserve(static_cast<int>(detection.edge_points.size()));
    for (const Eigen::Vector3f& p : detection.edge_points) *out.add_edge_points() = ToProto(p);
  }
  v1::StageTimings* t = out.mutable_timings();
  t->set_preprocess_ms(detection.timings.preprocess_ms);
  t->set_edge_points_ms(detection.timings.edge_points_ms);
  t->set_edge_segments_ms(detection.timings.edge_segments_ms);
  t->set_clubbing_ms(detection.timings.clubbing_ms);
  t->set_poses_ms(detection.timings.poses_ms);
  t->set_total_ms(detection.timings.total_ms);
  return out;
}

absl::StatusOr<Detection> DetectionFromProto(const v1::DetectResponse& response) {
  Detection out;
  absl::StatusOr<std::vector<DetectedBox>> boxes = BoxesFromProto(response);
  if (!boxes.ok()) return boxes.status();
  out.boxes = *std::move(boxes);
  out.segments.reserve(static_cast<size_t>(response.segments_size()));
  for (const v1::EdgeSegment& s : response.segments()) {
    EdgeSegment segment;
    segment.end1 = Vector3fFromProto(s.end1());
    segment.end2 = Vector3fFromProto(s.end2());
    segment.point = segment.end1;
    const Eigen::Vector3f d = segment.end2 - segment.end1;
    if (d.norm() > 0.0f) segment.direction = d.normalized();
    segment.num_points = static_cast<int>(s.num_points());
    out.segments.push_back(segment);
  }
  out.corners.reserve(static_cast<size_t>(response.corners_size()));
  for (const v1::Corner& c : response.corners()) {
    Corner corner;
    corner.position = Vector3fFromProto(c.position());
    out.corners.push_back(corner);
  }
  out.edge_points.reserve(static_cast<size_t>(response.edge_points_size()));
  for (const v1::Vector3& p : response.edge_points()) {
    out.edge_points.push_back(Vector3fFromProto(p));
  }
  const v1::StageTimings& t = response.timings();
  out.timings.preprocess_ms = t.preprocess_ms();
  out.timings.edge_points_ms = t.edge_points_ms();
  out.timings.edge_segments_ms = t.edge_segments_ms();
  out.timings.clubbing_ms = t.clubbing_ms();
  out.timings.poses_ms = t.poses_ms();
  out.timings.total_ms = t.total_ms();
  return out;
}

}  // namespace cornerpose::wire
