#include "common/perception/detector.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <utility>

#include "absl/strings/str_cat.h"
#include "common/perception/camera_model.h"
#include "common/perception/internal/box_overlap.h"
#include "common/perception/internal/hypothesis_judge.h"
#include "common/perception/neighbour_hypotheses.h"
#include "common/validation/range_check.h"

namespace cornerpose {
namespace {

using Clock = std::chrono::steady_clock;
double MsSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

// Points with a NaN, an infinity or a coordinate beyond any depth camera's
// range in any axis become NaN points (no return), so one bad value cannot
// poison the intrinsics fit or a neighbourhood; in a camera frame (organized)
// so do depths nearer than any depth camera measures (the pixel radius
// r fx / z grows without bound as z -> 0). Copies only when needed.
const PointCloud& SanitizeCloud(const PointCloud& cloud, PointCloud* storage) {
  constexpr float kMaxCoordinate = 100.0f;  // metres
  constexpr float kMinCameraDepthM = 0.01f;  // depth cameras' minimum range is centimetres
  const float min_depth = cloud.organized() ? kMinCameraDepthM : -kMaxCoordinate;
  auto bad = [min_depth](const Eigen::Vector3f& p) {
    return !(std::abs(p.x()) <= kMaxCoordinate && std::abs(p.y()) <= kMaxCoordinate &&
             p.z() >= min_depth && p.z() <= kMaxCoordinate) &&
           !(std::isnan(p.x()) && std::isnan(p.y()) && std::isnan(p.z()));
  };
  if (std::none_of(cloud.xyz.begin(), cloud.xyz.end(), bad)) return cloud;
  *storage = cloud;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (Eigen::Vector3f& p : storage->xyz) {
    if (bad(p)) p = Eigen::Vector3f(nan, nan, nan);
  }
  return *storage;
}

// Median depth of the valid points (every 7th), 0 when none.
double MedianDepth(const std::vector<float>& z) {
  std::vector<float> valid;
  for (size_t i = 0; i < z.size(); i += 7) {
    if (std::isfinite(z[i]) && z[i] > 0.0f) valid.push_back(z[i]);
  }
  if (valid.empty()) return 0.0;
  std::nth_element(valid.begin(), valid.begin() + valid.size() / 2, valid.end());
  return valid[valid.size() / 2];
}

void ApplySizeTolerance(double t, DetectorOptions* o) {
  o->faces.size_tolerance_m = t;
  o->refinement.tile_tolerance_m = 2.0 * t / 3.0;
  o->pose.length_tolerance_m = t + 0.01;
  o->acceptance.extent_tolerance_m = t + 0.01;
}

// The strongest declined hypotheses: none that overlaps a returned box (a
// variant of it) or a stronger declined one.
std::vector<DeclinedCandidate> StrongestDeclined(std::vector<DeclinedCandidate> all,
                                                 const std::vector<DetectedBox>& boxes,
                                                 const DetectorOptions& o) {
  std::stable_sort(all.begin(), all.end(), [](const DeclinedCandidate& a, const DeclinedCandidate& b) {
    return a.score > b.score;
  });
  std::vector<DeclinedCandidate> out;
  for (DeclinedCandidate& d : all) {
    if (static_cast<int>(out.size()) >= o.max_declined) break;
    auto overlaps = [&](const Eigen::Isometry3d& pose) {
      return internal::BoxesOverlap(pose, d.camera_T_box, o.box, o.acceptance.overlap_margin_m);
    };
    if (std::any_of(boxes.begin(), boxes.end(),
                    [&](const DetectedBox& b) { return overlaps(b.camera_T_box); }) ||
        std::any_of(out.begin(), out.end(),
                    [&](const DeclinedCandidate& c) { return overlaps(c.camera_T_box); })) {
      continue;
    }
    out.push_back(std::move(d));
  }
  return out;
}

}  // namespace

void DeriveGeometryParameters(double z, double focal_px, DetectorOptions* o) {
  const DetectorOptions defaults;
  const double smallest = std::min({o->box.l, o->box.b, o->box.h});
  double r = std::max(0.02, z > 0.0 && focal_px > 0.0 ? 6.0 * z / focal_px : 0.0);
  r = std::min(r, 0.35 * smallest);
  // To half a millimetre: finer is below the depth noise, and a box whose
  // rule lands within a hair of the default (a brick: 0.35 x 57 mm) keeps it.
  r = std::round(r * 2000.0) / 2000.0;
  if (o->edge_points.radius_m == defaults.edge_points.radius_m) {
    o->edge_points.radius_m = r;
    if (o->segments.gap_m == defaults.segments.gap_m) o->segments.gap_m = r;
  }
  if (o->segments.ransac_threshold_m == defaults.segments.ransac_threshold_m) {
    o->segments.ransac_threshold_m = r / 2.0;
  }
  if (o->clubbing.meet_distance_m == defaults.clubbing.meet_distance_m) {
    o->clubbing.meet_distance_m = r / 2.0;
  }
  if (o->evidence.outline_margin_m == defaults.evidence.outline_margin_m) {
    o->evidence.outline_margin_m = r / 2.0;
  }
}

absl::Status AcceptanceOptions::Validate() const {
  for (absl::Status s : {
           CheckRange("acceptance.min_support", min_support, 0.0, 1.0),
           CheckRange("acceptance.min_grasp_support", min_grasp_support, 0.0, 1.0),
           CheckRange("acceptance.max_grasp_occluded", max_grasp_occluded, 0.0, 1.0),
           CheckRange("acceptance.max_occluded", max_occluded, 0.0, 1.0),
           CheckRange("acceptance.max_see_through", max_see_through, 0.0, 1.0),
           CheckRange("acceptance.min_grasp_pixels", min_grasp_pixels, 1, 1'000'000),
           CheckPositive("acceptance.extent_tolerance_m", extent_tolerance_m, 1.0),
           CheckRange("acceptance.max_grasp_view_angle_deg", max_grasp_view_angle_deg, 0.0, 90.0),
           CheckRange("acceptance.border_margin_px", border_margin_px, 0.0, 1000.0),
           CheckRange("acceptance.overlap_margin_m", overlap_margin_m, 0.0, 1.0),
       }) {
    if (!s.ok()) return s;
  }
  return absl::OkStatus();
}

absl::Status DetectorOptions::Validate() const {
  if (absl::Status s = box.Validate(); !s.ok()) return s;
  for (absl::Status s :
       {edge_points.Validate(), segments.Validate(), clubbing.Validate(), pose.Validate(),
        refinement.Validate(), evidence.Validate(), acceptance.Validate(), faces.Validate()}) {
    if (!s.ok()) return s;
  }
  if (size_tolerance_m && !(*size_tolerance_m > 0.0 && *size_tolerance_m <= 0.1)) {
    return absl::InvalidArgumentError(
        absl::StrCat("size_tolerance_m=", *size_tolerance_m, " is outside (0, 0.1]"));
  }
  if (max_declined < 0 || max_declined > 1000) {
    return absl::InvalidArgumentError(
        absl::StrCat("max_declined=", max_declined, " is outside [0, 1000]"));
  }
  if (camera) {
    if (absl::Status s = camera->Validate(); !s.ok()) return s;
  }
  if (num_threads < 1 || num_threads > 256) {
    return absl::InvalidArgumentError(
        absl::StrCat("num_threads=", num_threads, " is outside [1, 256]"));
  }
  if (max_points < 1) return absl::InvalidArgumentError("max_points must be positive");
  return absl::OkStatus();
}

void SetEdgeRadius(double radius_m, DetectorOptions* options) {
  options->edge_points.radius_m = radius_m;
  options->segments.gap_m = radius_m;
}

void UseFrameCamera(const std::optional<CameraIntrinsics>& frame_camera, DetectorOptions* options) {
  if (frame_camera) options->camera = frame_camera;
}

absl::StatusOr<Detection> DetectBoxes(const PointCloud& input, const DetectorOptions& options_in) {
  const Clock::time_point t_start = Clock::now();
  if (absl::Status s = options_in.Validate(); !s.ok()) return s;
  if (absl::Status s = input.Validate(); !s.ok()) return s;
  PointCloud sanitized;
  const PointCloud& cloud = SanitizeCloud(input, &sanitized);
  if (cloud.size() > static_cast<size_t>(options_in.max_points)) {
    return absl::InvalidArgumentError(absl::StrCat(
        "cloud has ", cloud.size(), " points, above the limit of ", options_in.max_points));
  }
  DetectorOptions options = options_in;
  options.edge_points.num_threads = options.num_threads;
  Detection det;

  // Preprocess: the camera and its depth image.
  CameraIntrinsics camera = options.camera.value_or(CameraIntrinsics{});
  if (cloud.organized()) {
    absl::StatusOr<CameraIntrinsics> k = EstimateIntrinsics(cloud);
    if (!k.ok()) {  // too few valid points to hold a box
      det.timings.total_ms = MsSince(t_start);
      return det;
    }
    if (absl::Status s = k->Validate(); !s.ok()) {
      return absl::InvalidArgumentError(
          absl::StrCat("the organized cloud's points imply implausible ", s.message()));
    }
    camera = *k;
  }
  // A single-view unorganized cloud is laid back onto the camera's pixel
  // grid, so it takes the same (fast, shadow-aware) path as a frame.
  // A cloud that is not in a camera's frame (a merged scan, an object
  // model) mostly falls outside the image: it keeps the k-d tree path.
  PointCloud projected;
  bool project = !cloud.organized() && options.project_unorganized;
  if (project) {
    projected = OrganizeByProjection(cloud, camera);
    PointCloud in_range;  // the projected frame gets a camera's depth range
    if (&SanitizeCloud(projected, &in_range) != &projected) projected = std::move(in_range);
    const auto valid = [](const std::vector<Eigen::Vector3f>& xyz) {
      return std::count_if(xyz.begin(), xyz.end(), PointCloud::IsValid);
    };
    project = 2 * valid(projected.xyz) >= valid(cloud.xyz);
  }
  const PointCloud& work = project ? projected : cloud;
  const DepthImage depth = MakeDepthImage(work, camera);
  if (options.parameters_from_geometry) {
    DeriveGeometryParameters(MedianDepth(depth.z), camera.fx, &options);
  }
  if (options.size_tolerance_m) ApplySizeTolerance(*options.size_tolerance_m, &options);
  det.timings.preprocess_ms = MsSince(t_start);

  Clock::time_point t0 = Clock::now();
  absl::StatusOr<EdgePoints> edges = DetectEdgePoints(work, options.edge_points, camera.fx);
  if (!edges.ok()) return edges.status();
  det.edge_points = edges->points;
  det.timings.edge_points_ms = MsSince(t0);

  t0 = Clock::now();
  absl::StatusOr<std::vector<EdgeSegment>> segments =
      FitEdgeSegments(det.edge_points, options.segments);
  if (!segments.ok()) return segments.status();
  det.segments = *std::move(segments);
  det.timings.edge_segments_ms = MsSince(t0);

  t0 = Clock::now();
  absl::StatusOr<SegmentGroups> groups = ClubSegments(det.segments, options.clubbing);
  if (!groups.ok()) return groups.status();
  det.corners = groups->corners;
  det.timings.clubbing_ms = MsSince(t0);

  t0 = Clock::now();
  // Corners of each segment's group, for the paper's corner refinement.
  std::vector<int> group_of(det.segments.size(), -1);
  for (size_t g = 0; g < groups->groups.size(); ++g) {
    for (int s : groups->groups[g]) group_of[s] = static_cast<int>(g);
  }
  std::vector<std::vector<Eigen::Vector3d>> group_corners(groups->groups.size());
  for (const Corner& c : det.corners) {
    group_corners[group_of[c.segment_a]].push_back(c.position.cast<double>());
  }

  std::vector<DeclinedCandidate> declined;
  // Planar patches and their tilings first: every hypothesis, corner or
  // face, is checked against the layer its face lies on.
  FaceProposals faces;
  if (options.face_proposals) {
    const Clock::time_point t_faces = Clock::now();
    faces = ProposeFromFaces(depth, options.box, options.faces);
    det.timings.faces_ms = MsSince(t_faces);
  }
  internal::HypothesisJudge judge(depth, options);
  for (const Corner& c : det.corners) {
    const EdgeSegment& sa = det.segments[c.segment_a];
    const EdgeSegment& sb = det.segments[c.segment_b];
    const Eigen::Vector3d p1 = c.position.cast<double>();
    const Eigen::Vector3d fa = (c.a_at_end1 ? sa.end2 : sa.end1).cast<double>();
    const Eigen::Vector3d fb = (c.b_at_end1 ? sb.end2 : sb.end1).cast<double>();
    const double la = (fa - p1).norm(), lb = (fb - p1).norm();
    if (la < 1e-3 || lb < 1e-3) continue;
    for (const AxisAssignment& as : MatchEdgeLengths(la, lb, options.box, options.pose)) {
      Eigen::Isometry3d pose = PoseFromCorner(p1, fa - p1, fb - p1, as, options.box);
      const int corners = 1 + RefineWithCorners(group_corners[group_of[c.segment_a]], options.box,
                                                options.pose, &pose);
      judge.Propose(pose, corners, {c.segment_a, c.segment_b});
    }
  }
  // Best first; a box overlapping an accepted one is the same box or a
  // contradiction, and is dropped. Each accepted box proposes its
  // neighbours, which are judged the same way and may propose theirs.
  auto overlaps_kept = [&](const Eigen::Isometry3d& pose) {
    return std::any_of(det.boxes.begin(), det.boxes.end(), [&](const DetectedBox& kept) {
      return internal::BoxesOverlap(kept.camera_T_box, pose, options.box,
                                    options.acceptance.overlap_margin_m);
    });
  };
  auto accept_all = [&] {
    std::vector<internal::Candidate> pending = judge.Evaluate(options.num_threads);
    while (!pending.empty()) {
      std::stable_sort(pending.begin(), pending.end(),
                       [](const internal::Candidate& a, const internal::Candidate& b) {
                         return a.box.score > b.box.score;
                       });
      for (internal::Candidate& c : pending) {
        if (overlaps_kept(c.box.camera_T_box)) continue;
        // Only a box that some side's seam (or tiling) bounds: one ended by
        // depth jumps on every side is measured, whatever patch it is on.
        const bool bounded_by_seams = std::any_of(
            c.refinement.sides.begin(), c.refinement.sides.end(), [](SideKind k) {
              return k == SideKind::kSeam || k == SideKind::kTiled || k == SideKind::kContinues;
            });
        if (std::string why = bounded_by_seams ? LayerContradiction(faces, depth, options.box,
                                                                    c.box.camera_T_box,
                                                                    c.box.grasp_centre_camera,
                                                                    c.box.grasp_normal_camera,
                                                                    options.faces)
                                               : std::string();
            !why.empty()) {
          declined.push_back({c.box.camera_T_box, c.box.score, std::move(why)});
          continue;
        }
        det.boxes.push_back(c.box);
        if (options.propagate_to_neighbours) {
          for (const Eigen::Isometry3d& pose :
               NeighbourHypotheses(c.box, options.box, options.neighbour_gap_m)) {
            judge.Propose(pose, 0, {});
          }
        }
      }
      pending = judge.Evaluate(options.num_threads);
    }
  };
  accept_all();
  // Face proposals after the corner ones: a tile on a box already found is
  // not judged again.
  if (options.face_proposals) {
    for (const Eigen::Isometry3d& pose : faces.poses) {
      if (!overlaps_kept(pose)) judge.Propose(pose, 0, {}, true);
    }
    for (DeclinedCandidate& d : faces.declined) {
      d.score = MeasureBox(depth, d.camera_T_box, options.box, options.evidence).support();
      declined.push_back(std::move(d));
    }
    accept_all();
  }
  std::stable_sort(det.boxes.begin(), det.boxes.end(),
                   [](const DetectedBox& a, const DetectedBox& b) { return a.score > b.score; });
  det.hypotheses = judge.stats();
  declined.insert(declined.end(), judge.declined().begin(), judge.declined().end());
  det.declined = StrongestDeclined(std::move(declined), det.boxes, options);
  det.timings.poses_ms = MsSince(t0);
  det.timings.total_ms = MsSince(t_start);
  return det;
}

}  // namespace cornerpose
