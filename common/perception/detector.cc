#include "common/perception/detector.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <utility>

#include "absl/strings/str_cat.h"
#include "common/perception/camera_model.h"
#include "common/perception/internal/box_overlap.h"
#include "common/perception/neighbour_hypotheses.h"
#include "common/perception/pose_error.h"

namespace cornerpose {
namespace {

using Clock = std::chrono::steady_clock;
double MsSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

struct Candidate {
  DetectedBox box;
  BoxEvidence evidence;
  RefinementResult refinement;
};

// Judges a refined hypothesis; returns its score, or < 0 when rejected.
double Judge(const BoxEvidence& ev, const RefinementResult& ref, const BoxDims& dims,
             BoxFace grasp, const AcceptanceOptions& o) {
  if (!ev.in_front_of_camera || !ref.ok) return -1.0;
  const FaceEvidence& g = ev.faces[static_cast<int>(grasp)];
  if (g.expected < o.min_grasp_pixels) return -1.0;
  const double grasp_occluded = static_cast<double>(g.occluded) / g.expected;
  const double grasp_support = g.visible() > 0 ? static_cast<double>(g.agree) / g.visible() : 0.0;
  if (grasp_occluded > o.max_grasp_occluded || grasp_support < o.min_grasp_support) return -1.0;
  if (ev.support() < o.min_support || ev.see_through_fraction() > o.max_see_through) return -1.0;
  // A box mostly hidden behind what is in front of it is more often a box
  // pushed through a surface (the floor, a neighbour) than a real one.
  if (ev.total.expected > 0 &&
      static_cast<double>(ev.total.occluded) / ev.total.expected > o.max_occluded) {
    return -1.0;
  }
  // The in-plane position must be measured, not guessed: a free side along
  // each of the face's axes.
  const int fi = static_cast<int>(grasp);
  const int axis_a = (fi / 2 + 1) % 3, axis_b = (fi / 2 + 2) % 3;
  if (ref.extent_a_m > 0.0 && std::abs(ref.extent_a_m - dims[axis_a]) > o.extent_tolerance_m) {
    return -1.0;
  }
  if (ref.extent_b_m > 0.0 && std::abs(ref.extent_b_m - dims[axis_b]) > o.extent_tolerance_m) {
    return -1.0;
  }
  // Every side that can be seen must end the face: a free border or a seam
  // to a touching box. A face that runs on flat is a bigger face.
  int measured = 0;
  for (SideKind k : ref.sides) {
    if (k == SideKind::kContinues) return -1.0;
    measured += k == SideKind::kFree || k == SideKind::kSeam || k == SideKind::kTiled;
  }
  // At least two sides pin the face down; a face with no free side must be
  // boxed in on all four (by seams or whole tiles of its layer).
  if (measured < 2 || (ref.free_sides < 1 && measured < 4)) return -1.0;
  // A side hidden under something may hide more face: keep the box only if
  // no bigger side of the box could stand in for this one there.
  for (int s = 0; s < 4; ++s) {
    if (ref.sides[s] != SideKind::kOccluded) continue;
    const int here = s < 2 ? axis_a : axis_b, other = s < 2 ? axis_b : axis_a;
    for (int k = 0; k < 3; ++k) {
      if (k != here && k != other && dims[k] > dims[here] + o.extent_tolerance_m) return -1.0;
      if (k == other && dims[k] > dims[here] + o.extent_tolerance_m &&
          ref.sides[s < 2 ? 2 : 0] == SideKind::kOccluded) {
        return -1.0;
      }
    }
  }
  return std::clamp(0.5 * grasp_support + 0.5 * ev.support() - 2.0 * ev.see_through_fraction() -
                        0.25 * grasp_occluded,
                    0.0, 1.0);
}

// Checks pose hypotheses against the depth image: a cheap render-and-compare
// first, then refinement on the grasp face and the full judgement. Poses it
// has already seen (same place, same orientation up to the box's symmetries)
// are skipped, since corners of one box propose it many times.
class HypothesisJudge {
 public:
  HypothesisJudge(const DepthImage& depth, const DetectorOptions& options)
      : depth_(depth), options_(options), symmetries_(BoxSymmetries(options.box)) {}

  void Consider(const Eigen::Isometry3d& pose_in, int corners, std::vector<int> segments) {
    if (Seen(pose_in)) return;
    seen_.push_back(pose_in);
    ++stats_.proposed;
    Candidate cand;
    cand.box.camera_T_box = pose_in;
    cand.box.num_corners = corners;
    cand.box.segments = std::move(segments);
    const BoxEvidence first = MeasureBox(depth_, pose_in, options_.box, options_.evidence);
    // Refinement moves a hypothesis by centimetres at most: one that the
    // depth image already rejects by a wide margin is not worth refining.
    const BoxFace grasp = first.grasp_face;
    const FaceEvidence& g = first.faces[static_cast<int>(grasp)];
    if (!first.in_front_of_camera || first.see_through_fraction() > 0.2 ||
        first.support() < 0.4 || g.visible() <= 0 ||
        static_cast<double>(g.agree) / g.visible() < 0.5) {
      return;
    }
    // Unrefined corners can be a centimetre off: only the refined face must
    // lie inside the image (checked below).
    if (!GraspFaceInView(pose_in, grasp, -20.0)) return;
    ++stats_.refined;
    cand.refinement = RefineOnGraspFace(depth_, options_.box, grasp, options_.refinement,
                                        &cand.box.camera_T_box);
    cand.evidence = MeasureBox(depth_, cand.box.camera_T_box, options_.box, options_.evidence);
    const double score =
        Judge(cand.evidence, cand.refinement, options_.box, grasp, options_.acceptance);
    if (score < 0.0 ||
        !GraspFaceInView(cand.box.camera_T_box, grasp, options_.acceptance.border_margin_px)) {
      return;
    }
    cand.box.score = score;
    cand.box.grasp_face = cand.evidence.grasp_face;
    const Eigen::Vector3d n_box = BoxFaceNormal(cand.box.grasp_face);
    const int axis = static_cast<int>(cand.box.grasp_face) / 2;
    cand.box.grasp_normal_camera = cand.box.camera_T_box.linear() * n_box;
    cand.box.grasp_centre_camera = cand.box.camera_T_box * (n_box * options_.box[axis] / 2.0);
    accepted_.push_back(std::move(cand));
    ++stats_.accepted;
  }

  const HypothesisStats& stats() const { return stats_; }

  std::vector<Candidate> TakeAccepted() { return std::exchange(accepted_, {}); }

 private:
  // A face cut by the image border cannot be checked to its end (and a
  // gripper aimed at its centre may miss the box): such boxes are not
  // returned.
  bool GraspFaceInView(const Eigen::Isometry3d& pose, BoxFace face, double margin) const {
    const int f = static_cast<int>(face);
    const int n = f / 2, a = (n + 1) % 3, b = (n + 2) % 3;
    const CameraIntrinsics& k = depth_.camera;
    for (double sa : {-0.5, 0.5}) {
      for (double sb : {-0.5, 0.5}) {
        Eigen::Vector3d local = Eigen::Vector3d::Zero();
        local[n] = (f % 2 == 0 ? 0.5 : -0.5) * options_.box[n];
        local[a] = sa * options_.box[a];
        local[b] = sb * options_.box[b];
        const Eigen::Vector3d p = pose * local;
        if (p.z() <= 0.05) return false;
        const Eigen::Vector2d px = Project(k, p);
        if (px.x() < margin || px.y() < margin || px.x() > k.width - 1 - margin ||
            px.y() > k.height - 1 - margin) {
          return false;
        }
      }
    }
    return true;
  }

  bool Seen(const Eigen::Isometry3d& pose) const {
    for (const Eigen::Isometry3d& s : seen_) {
      if ((s.translation() - pose.translation()).norm() > 0.01) continue;
      for (const Eigen::Matrix3d& S : symmetries_) {
        if ((s.linear() - pose.linear() * S).norm() < 0.06) return true;  // ~2.5 degrees
      }
    }
    return false;
  }

  const DepthImage& depth_;
  const DetectorOptions& options_;
  const std::vector<Eigen::Matrix3d> symmetries_;
  std::vector<Eigen::Isometry3d> seen_;
  std::vector<Candidate> accepted_;
  HypothesisStats stats_;
};

// Points with a NaN, an infinity or a coordinate beyond any depth camera's
// range in any axis become NaN points (no return), so one bad value cannot
// poison the intrinsics fit or a neighbourhood. Copies only when needed.
const PointCloud& SanitizeCloud(const PointCloud& cloud, PointCloud* storage) {
  constexpr float kMaxCoordinate = 100.0f;  // metres
  auto bad = [](const Eigen::Vector3f& p) {
    return !(std::abs(p.x()) <= kMaxCoordinate && std::abs(p.y()) <= kMaxCoordinate &&
             std::abs(p.z()) <= kMaxCoordinate) &&
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

}  // namespace

absl::Status AcceptanceOptions::Validate() const {
  for (double v : {min_support, min_grasp_support, max_grasp_occluded, max_see_through}) {
    if (!(v >= 0.0 && v <= 1.0)) {
      return absl::InvalidArgumentError(
          absl::StrCat("acceptance fraction ", v, " is outside [0, 1]"));
    }
  }
  if (min_grasp_pixels < 1 || !(extent_tolerance_m > 0.0) || !(overlap_margin_m >= 0.0)) {
    return absl::InvalidArgumentError("acceptance limits out of range");
  }
  return absl::OkStatus();
}

absl::Status DetectorOptions::Validate() const {
  if (absl::Status s = box.Validate(); !s.ok()) return s;
  for (absl::Status s : {edge_points.Validate(), segments.Validate(), clubbing.Validate(),
                         pose.Validate(), refinement.Validate(), evidence.Validate(),
                         acceptance.Validate()}) {
    if (!s.ok()) return s;
  }
  if (camera) {
    if (absl::Status s = camera->Validate(); !s.ok()) return s;
  }
  if (num_threads < 1 || num_threads > 256) {
    return absl::InvalidArgumentError(absl::StrCat("num_threads=", num_threads, " is outside [1, 256]"));
  }
  if (max_points < 1) return absl::InvalidArgumentError("max_points must be positive");
  return absl::OkStatus();
}

absl::StatusOr<Detection> DetectBoxes(const PointCloud& input, const DetectorOptions& options_in) {
  const Clock::time_point t_start = Clock::now();
  if (absl::Status s = options_in.Validate(); !s.ok()) return s;
  if (absl::Status s = input.Validate(); !s.ok()) return s;
  PointCloud sanitized;
  const PointCloud& cloud = SanitizeCloud(input, &sanitized);
  if (cloud.size() > static_cast<size_t>(options_in.max_points)) {
    return absl::InvalidArgumentError(absl::StrCat("cloud has ", cloud.size(),
                                                   " points, above the limit of ",
                                                   options_in.max_points));
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
    camera = *k;
  }
  // A single-view unorganized cloud is laid back onto the camera's pixel
  // grid, so it takes the same (fast, shadow-aware) path as a frame.
  PointCloud projected;
  const bool project = !cloud.organized() && options.project_unorganized;
  if (project) projected = OrganizeByProjection(cloud, camera);
  const PointCloud& work = project ? projected : cloud;
  const DepthImage depth = MakeDepthImage(work, camera);
  det.timings.preprocess_ms = MsSince(t_start);

  Clock::time_point t0 = Clock::now();
  absl::StatusOr<EdgePoints> edges = DetectEdgePoints(work, options.edge_points, camera.fx);
  if (!edges.ok()) return edges.status();
  det.edge_points = edges->points;
  det.timings.edge_points_ms = MsSince(t0);

  t0 = Clock::now();
  absl::StatusOr<std::vector<EdgeSegment>> segments = FitEdgeSegments(det.edge_points, options.segments);
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

  HypothesisJudge judge(depth, options);
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
      judge.Consider(pose, corners, {c.segment_a, c.segment_b});
    }
  }
  // Best first; a box overlapping an accepted one is the same box or a
  // contradiction, and is dropped. Each accepted box proposes its
  // neighbours, which are judged the same way and may propose theirs.
  std::vector<Candidate> pending = judge.TakeAccepted();
  while (!pending.empty()) {
    std::stable_sort(pending.begin(), pending.end(), [](const Candidate& a, const Candidate& b) {
      return a.box.score > b.box.score;
    });
    for (Candidate& c : pending) {
      bool clash = false;
      for (const DetectedBox& kept : det.boxes) {
        if (internal::BoxesOverlap(kept.camera_T_box, c.box.camera_T_box, options.box,
                                   options.acceptance.overlap_margin_m)) {
          clash = true;
          break;
        }
      }
      if (clash) continue;
      det.boxes.push_back(c.box);
      if (options.propagate_to_neighbours) {
        for (const Eigen::Isometry3d& pose :
             NeighbourHypotheses(c.box, options.box, options.neighbour_gap_m)) {
          judge.Consider(pose, 0, {});
        }
      }
    }
    pending = judge.TakeAccepted();
  }
  std::stable_sort(det.boxes.begin(), det.boxes.end(),
                   [](const DetectedBox& a, const DetectedBox& b) { return a.score > b.score; });
  det.hypotheses = judge.stats();
  det.timings.poses_ms = MsSince(t0);
  det.timings.total_ms = MsSince(t_start);
  return det;
}

}  // namespace cornerpose
