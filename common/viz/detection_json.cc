#include "common/viz/detection_json.h"

#include <cerrno>
#include <fstream>
#include <nlohmann/json.hpp>

#include "absl/strings/str_cat.h"

namespace cornerpose {
namespace {

template <typename Derived>
nlohmann::json Vec(const Eigen::MatrixBase<Derived>& v) {
  nlohmann::json out = nlohmann::json::array();
  for (int i = 0; i < v.size(); ++i) out.push_back(static_cast<double>(v[i]));
  return out;
}

// Row-major nested 4x4, as the scorer and the GT files store poses.
nlohmann::json Pose(const Eigen::Isometry3d& pose) {
  const Eigen::Matrix4d m = pose.matrix();
  nlohmann::json rows = nlohmann::json::array();
  for (int r = 0; r < 4; ++r) rows.push_back(Vec(m.row(r).transpose()));
  return rows;
}

// What proposed a box: a corner of edge segments, a planar patch's tiling,
// two parallel edge segments (no corner), or a box found beside it.
const char* ProposedBy(const DetectedBox& box) {
  if (box.from_face) return "face";
  if (box.num_corners > 0) return "corner";
  return box.segments.empty() ? "neighbour" : "edges";
}

}  // namespace

nlohmann::json DetectionToJson(const Detection& detection, const BoxDims& dims) {
  nlohmann::json out;
  out["box_dims"] = {dims.l, dims.b, dims.h};

  nlohmann::json boxes = nlohmann::json::array();
  nlohmann::json detections = nlohmann::json::array();
  for (const DetectedBox& box : detection.boxes) {
    boxes.push_back({{"camera_T_box", Pose(box.camera_T_box)},
                     {"score", box.score},
                     {"grasp_face", BoxFaceName(box.grasp_face)},
                     {"grasp_centre", Vec(box.grasp_centre_camera)},
                     {"grasp_normal", Vec(box.grasp_normal_camera)},
                     {"num_corners", box.num_corners},
                     {"segments", box.segments},
                     {"measured_extent", {box.measured_extent_m[0], box.measured_extent_m[1]}},
                     {"proposed_by", ProposedBy(box)}});
    detections.push_back({{"pose", Pose(box.camera_T_box)}, {"score", box.score}});
  }
  out["boxes"] = std::move(boxes);

  nlohmann::json declined = nlohmann::json::array();
  for (const DeclinedCandidate& d : detection.declined) {
    declined.push_back(
        {{"camera_T_box", Pose(d.camera_T_box)}, {"score", d.score}, {"reason", d.reason}});
  }
  out["declined"] = std::move(declined);

  nlohmann::json edges = nlohmann::json::array();
  for (const EdgeSegment& s : detection.segments) {
    edges.push_back({{"end1", Vec(s.end1)},
                     {"end2", Vec(s.end2)},
                     {"num_points", s.num_points},
                     {"length", s.length()}});
  }
  out["edges"] = std::move(edges);

  nlohmann::json corners = nlohmann::json::array();
  for (const Corner& c : detection.corners) {
    corners.push_back({{"position", Vec(c.position)}, {"segments", {c.segment_a, c.segment_b}}});
  }
  out["corners"] = std::move(corners);
  out["num_edge_points"] = detection.edge_points.size();

  const StageTimings& t = detection.timings;
  out["timings_ms"] = {{"preprocess", t.preprocess_ms},
                       {"edge_points", t.edge_points_ms},
                       {"edge_segments", t.edge_segments_ms},
                       {"clubbing", t.clubbing_ms},
                       {"faces", t.faces_ms},
                       {"poses", t.poses_ms},
                       {"total", t.total_ms}};
  out["detections"] = std::move(detections);
  out["time_s"] = t.total_ms / 1000.0;
  return out;
}

absl::Status WriteDetectionJson(const std::string& path, const Detection& detection,
                                const BoxDims& dims) {
  std::ofstream file(path);
  if (!file) {
    const int err = errno;
    const std::string message = absl::StrCat(path, ": cannot open for writing");
    return err != 0 ? absl::ErrnoToStatus(err, message) : absl::UnknownError(message);
  }
  file << DetectionToJson(detection, dims).dump(2) << '\n';
  file.close();
  if (!file) return absl::DataLossError(absl::StrCat(path, ": write failed"));
  return absl::OkStatus();
}

}  // namespace cornerpose
