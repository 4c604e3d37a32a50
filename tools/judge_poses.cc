// judge_poses: the detector's judge on poses you give it. For a frame and
// poses believed right (the ground truth of a generated frame, or a box an
// integrator measured by hand), prints what the judge makes of each: the
// first look's numbers, and after refinement the side kinds, the verdict
// and its reason. "Why was this box not found?" in one run: a pose the
// judge accepts was never proposed; one it declines says which test fails.
//
//   judge_poses --cloud F --box L,B,H|MODEL --poses GT.json [--intrinsics W,H,fx,fy,cx,cy]
//               [--color F] [--all] [--per_face]
//
// GT.json: make_frames' or the shared scorer's ground truth (boxes[] with
// T_cam_box; only pickable targets unless --all) or the detector's own
// --json (boxes[] with camera_T_box). --per_face prints the evidence's
// pixel counts per face of the box. Each pose is followed by the nearest
// face-first proposal (judged too when within 6 cm) and the planar patch
// under the pose's grasp face.
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "absl/strings/str_format.h"
#include "common/box/box_models.h"
#include "common/io/cloud_io.h"
#include "common/perception/box_evidence.h"
#include "common/perception/box_refinement.h"
#include "common/perception/camera_model.h"
#include "common/perception/detector.h"
#include "common/perception/face_proposals.h"
#include "common/perception/internal/border_faces.h"
#include "common/perception/internal/hypothesis_judge.h"
#include "nlohmann/json.hpp"
#include "tools/command_args.h"

namespace cornerpose::tools {
namespace {

const char* SideName(SideKind k) {
  switch (k) {
    case SideKind::kUnknown:
      return "unknown";
    case SideKind::kFree:
      return "free";
    case SideKind::kSeam:
      return "seam";
    case SideKind::kOccluded:
      return "occluded";
    case SideKind::kTiled:
      return "tiled";
    case SideKind::kContinues:
      return "continues";
  }
  return "?";
}

// Judges one pose step by step (first look, refinement, the acceptance
// test) and prints each step, then the verdict of the detector's own judge
// (internal::HypothesisJudge::JudgeAlone: also the view, floor and
// orientation tests that come after the acceptance test; the floor only
// when `judge` was given one); returns the grasp face.
BoxFace JudgeOne(const DepthImage& depth, const DetectorOptions& options,
                 const internal::HypothesisJudge& judge, const Eigen::Isometry3d& pose,
                 bool per_face) {
  const BoxEvidence first = MeasureBox(depth, pose, options.box, options.evidence);
  const FaceEvidence& g = first.faces[static_cast<int>(first.grasp_face)];
  std::printf(" first look support %.2f, grasp agree %.2f, see-through %.3f", first.support(),
              g.visible() > 0 ? static_cast<double>(g.agree) / g.visible() : 0.0,
              first.see_through_fraction());
  Eigen::Isometry3d refined = pose;
  const RefinementResult ref =
      RefineOnGraspFace(depth, options.box, first.grasp_face, options.refinement, &refined);
  const Eigen::Vector3d moved = refined.translation() - pose.translation();
  const double turned =
      Eigen::AngleAxisd(refined.linear() * pose.linear().transpose()).angle() * 180.0 / M_PI;
  std::printf("; refined %s (moved %.1f mm, %.2f deg), sides %s %s %s %s, plane rms %.1f mm",
              ref.ok ? "ok" : "FAILED", 1000.0 * moved.norm(), turned, SideName(ref.sides[0]),
              SideName(ref.sides[1]), SideName(ref.sides[2]), SideName(ref.sides[3]),
              1000.0 * ref.plane_rms_m);
  for (int side = 0; side < 4; ++side) {
    if (ref.past_gap[side]) std::printf(", plane past a gap beyond side %d", side);
  }
  // A side out of view that what is in view pins (internal/border_faces.h).
  const int out_of_view =
      options.acceptance.face_may_run_out_of_view
          ? internal::SideOutOfViewPinned(depth, refined, first.grasp_face, options.box, ref,
                                          options.acceptance, options.refinement.plane_tolerance_m)
          : -1;
  if (out_of_view >= 0) std::printf(", side %d out of view pinned", out_of_view);
  const BoxEvidence ev = MeasureBox(depth, refined, options.box, options.evidence);
  std::string reason;
  const double score = internal::JudgeRefined(
      ev, ref, options.box, first.grasp_face, options.acceptance, &reason, out_of_view,
      internal::LongerReadingsRuledOut(depth, refined, first.grasp_face, ref, options));
  if (per_face) {
    for (int fi = 0; fi < 6; ++fi) {
      const FaceEvidence& e = ev.faces[fi];
      if (e.expected + e.border == 0) continue;
      std::printf(
          "\n    face %s: expected %d agree %d occluded %d see-through %d missing %d border %d",
          BoxFaceName(static_cast<BoxFace>(fi)), e.expected, e.agree, e.occluded, e.see_through,
          e.missing, e.border);
    }
    std::printf("\n   ");
  }
  if (score >= 0.0) {
    std::printf("; ACCEPTED score %.2f", score);
  } else {
    std::printf("; declined: %s", reason.c_str());
  }
  std::string why;
  if (judge.JudgeAlone(pose, {}, &why)) {
    std::printf("; the detector's judge: ACCEPTED");
  } else {
    std::printf(
        "; the detector's judge: declined: %s",
        why.empty() ? "not refined (the first look, or the face not in view)" : why.c_str());
  }
  return first.grasp_face;
}

int Run(const CommandArgs& args) {
  absl::StatusOr<BoxDims> box = ParseBoxDims(*args.Get("box"));
  if (!box.ok()) {
    std::fprintf(stderr, "judge_poses: %s\n", box.status().ToString().c_str());
    return 1;
  }
  DetectorOptions options;
  options.box = *box;
  LoadOptions load;
  if (auto k = args.Get("intrinsics")) {
    absl::StatusOr<CameraIntrinsics> intrinsics = ParseIntrinsics(*k);
    if (!intrinsics.ok()) return 1;
    load.intrinsics = *intrinsics;
    options.camera = *intrinsics;
  }
  if (auto c = args.Get("color")) load.color_path = *c;
  absl::StatusOr<PointCloud> cloud = LoadPointCloud(*args.Get("cloud"), load);
  if (!cloud.ok() || !cloud->organized()) {
    std::fprintf(stderr, "judge_poses: need an organized frame\n");
    return 1;
  }
  CameraIntrinsics camera = options.camera.value_or(CameraIntrinsics{});
  if (absl::StatusOr<CameraIntrinsics> k = EstimateIntrinsics(*cloud); k.ok()) camera = *k;
  const DepthImage depth = MakeDepthImage(*cloud, camera);
  DeriveGeometryParameters(MedianDepth(depth), camera.fx, &options);

  std::ifstream in(*args.Get("poses"));
  const nlohmann::json doc = nlohmann::json::parse(in, nullptr, false);
  if (doc.is_discarded() || !doc.contains("boxes")) {
    std::fprintf(stderr, "judge_poses: %s is not a pose file\n", args.Get("poses")->c_str());
    return 1;
  }
  // The face-first proposals, to tell which boxes they reach.
  const FaceProposals faces = ProposeFromFaces(depth, options.box, options.faces);
  const internal::HypothesisJudge judge(depth, options);
  for (const nlohmann::json& b : doc["boxes"]) {
    const bool gt = b.contains("T_cam_box");
    if (gt && !args.Has("all") && !(b.value("target", false) && b.value("pickable", false))) {
      continue;
    }
    const nlohmann::json& m = gt ? b["T_cam_box"] : b["camera_T_box"];
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 4; ++c) pose.matrix()(r, c) = m[r][c].get<double>();
    }
    std::printf("box %s:", gt ? std::to_string(b.value("id", 0)).c_str() : "?");
    const BoxFace grasp_face = JudgeOne(depth, options, judge, pose, args.Has("per_face"));
    // The nearest face proposal, and the planar patch under the face's centre.
    double nearest = 1e9;
    const Eigen::Isometry3d* nearest_pose = nullptr;
    for (const Eigen::Isometry3d& f : faces.poses) {
      if ((f.translation() - pose.translation()).norm() < nearest) {
        nearest = (f.translation() - pose.translation()).norm();
        nearest_pose = &f;
      }
    }
    const int axis = static_cast<int>(grasp_face) / 2;
    const Eigen::Vector3d n_box = BoxFaceNormal(grasp_face);
    const Eigen::Vector3d centre = pose * (n_box * options.box[axis] / 2.0);
    const Eigen::Vector2d px = Project(camera, centre);
    const int patch = faces.patches.PatchAt(static_cast<int>(px.x()), static_cast<int>(px.y()));
    std::printf("; nearest face proposal %.0f mm", 1000.0 * nearest);
    if (patch >= 0) {
      const PlaneRectangle r = OutlineRectangle(faces.patches.patches[patch]);
      const PlanarPatch& pp = faces.patches.patches[patch];
      std::printf("; patch %d outline %.3f x %.3f m (%zu cells%s, %.0f deg to the view)", patch,
                  r.width, r.height, pp.points.size(), pp.touches_border ? ", at the border" : "",
                  std::acos(std::clamp(pp.normal.dot(-pp.centroid.normalized()), -1.0, 1.0)) *
                      180.0 / M_PI);
    } else {
      std::printf("; no patch at its centre");
    }
    std::printf("\n");
    if (nearest_pose != nullptr && nearest < 0.06) {
      const double turn =
          Eigen::AngleAxisd(nearest_pose->linear() * pose.linear().transpose()).angle() * 180.0 /
          M_PI;
      std::printf("  face proposal %.0f mm, %.0f deg off:", 1000.0 * nearest, turn);
      JudgeOne(depth, options, judge, *nearest_pose, args.Has("per_face"));
      std::printf("\n");
    }
  }
  return 0;
}

}  // namespace
}  // namespace cornerpose::tools

int main(int argc, char** argv) {
  using namespace cornerpose::tools;
  const std::vector<std::string> argv_list(argv + 1, argv + argc);
  absl::StatusOr<CommandArgs> args =
      ParseCommandArgs(argv_list, {"cloud", "box", "poses", "intrinsics", "color"},
                       {"all", "per_face"}, {"cloud", "box", "poses"});
  if (!args.ok()) {
    std::fprintf(stderr, "judge_poses: %s\n", std::string(args.status().message()).c_str());
    return 2;
  }
  return Run(*args);
}
