#include "server/http/view_json.h"

#include <cmath>
#include <nlohmann/json.hpp>

#include "absl/strings/str_cat.h"
#include "absl/time/time.h"
#include "server/http/frame_encoding.h"

namespace cornerpose::server {
namespace {

using nlohmann::json;

json Vec(const Eigen::Vector3f& v) { return json::array({v.x(), v.y(), v.z()}); }
json Vec(const Eigen::Vector3d& v) { return json::array({v.x(), v.y(), v.z()}); }
// Millimetre precision (0.1 mm) keeps the edge points short on the wire.
double Round4(double v) { return std::round(v * 1e4) / 1e4; }

json Summary(const SourceSummary& s) {
  json out = {{"name", s.name},
              {"description", s.description},
              {"state", SourceStateName(s.status.state)},
              {"state_reason", s.status.reason},
              {"box_model", s.box_label},
              {"frame_id", s.frame_id},
              {"fps", s.fps}};
  out["frame_age_s"] = s.frame_age_s ? json(*s.frame_age_s) : json(nullptr);
  out["detection_ms"] = s.detection_ms ? json(*s.detection_ms) : json(nullptr);
  return out;
}

}  // namespace

std::string SourceSummaryJson(const SourceSummary& summary) { return Summary(summary).dump(); }

std::string SourceListJson(const std::vector<SourceSummary>& summaries) {
  json list = json::array();
  for (const SourceSummary& s : summaries) list.push_back(Summary(s));
  return json{{"sources", list}}.dump();
}

std::string ViewDetectionJson(const ViewDetection& view) {
  const Frame& frame = *view.frame;
  const Detection& d = view.detection;
  // A cloud from a depth image has its camera; an organized cloud without
  // one gets the detector's (what its options used), else the default.
  const CameraIntrinsics k = FrameImageCamera(frame, view.options.camera);
  const std::string base =
      absl::StrCat("/api/sources/", frame.source, "/frames/", frame.id);
  json out = {
      {"source", frame.source},
      {"frame_id", frame.id},
      {"capture_time_unix_ms", absl::ToDoubleMilliseconds(frame.capture_time - absl::UnixEpoch())},
      {"box_model", view.box_label},
      {"box_dims", json::array({view.options.box.l, view.options.box.b, view.options.box.h})},
      {"intrinsics",
       {{"width", k.width}, {"height", k.height}, {"fx", k.fx}, {"fy", k.fy}, {"cx", k.cx},
        {"cy", k.cy}}},
      {"image",
       {{"url", base + "/image.png"},
        {"kind", frame.cloud.rgb.empty() ? "depth" : "color"},
        {"width", k.width},
        {"height", k.height}}},
  };
  const size_t cloud_points = ViewCloudIndices(frame.cloud).size();
  out["cloud"] = {{"url", base + "/cloud.bin"},
                  {"points", cloud_points},
                  {"has_rgb", !frame.cloud.rgb.empty()}};
  json boxes = json::array();
  for (const DetectedBox& b : d.boxes) {
    const Eigen::Matrix4d m = b.camera_T_box.matrix();
    json pose = json::array();
    for (int r = 0; r < 4; ++r) {
      pose.push_back(json::array({m(r, 0), m(r, 1), m(r, 2), m(r, 3)}));
    }
    boxes.push_back({{"camera_T_box", pose},
                     {"score", b.score},
                     {"grasp_face", BoxFaceName(b.grasp_face)},
                     {"grasp_centre", Vec(b.grasp_centre_camera)},
                     {"grasp_normal", Vec(b.grasp_normal_camera)}});
  }
  out["boxes"] = boxes;
  json segments = json::array();
  for (const EdgeSegment& s : d.segments) {
    segments.push_back({{"end1", Vec(s.end1)}, {"end2", Vec(s.end2)}, {"num_points", s.num_points}});
  }
  out["segments"] = segments;
  json corners = json::array();
  for (const Corner& c : d.corners) corners.push_back(Vec(c.position));
  out["corners"] = corners;
  std::vector<double> edges;
  edges.reserve(d.edge_points.size() * 3);
  for (const Eigen::Vector3f& p : d.edge_points) {
    for (int i = 0; i < 3; ++i) edges.push_back(Round4(p[i]));
  }
  out["edge_points"] = edges;
  out["num_edge_points"] = d.edge_points.size();
  const StageTimings& t = d.timings;
  out["timings_ms"] = {{"preprocess", t.preprocess_ms},   {"edge_points", t.edge_points_ms},
                       {"edge_segments", t.edge_segments_ms}, {"clubbing", t.clubbing_ms},
                       {"poses", t.poses_ms},             {"total", t.total_ms}};
  return out.dump();
}

std::string ErrorJson(const std::string& message) { return json{{"error", message}}.dump(); }

}  // namespace cornerpose::server
