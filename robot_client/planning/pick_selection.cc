#include "robot_client/planning/pick_selection.h"

#include <algorithm>
#include <array>
#include <limits>
#include <utility>

#include "absl/strings/str_format.h"

namespace cornerpose::robot_client {
namespace {

std::string Xyz(const Eigen::Vector3d& p) {
  return absl::StrFormat("(%.3f, %.3f, %.3f)", p.x(), p.y(), p.z());
}

// Empty when one of the four grasps has G, M and R inside the workspace and
// reachable; otherwise why the first (least wrist rotation) grasp fails.
std::string CheckPickWaypoints(const BoxInBase& box, const Workspace& workspace,
                               const WaypointOptions& waypoints, const Reachability& reachable) {
  const std::array<Eigen::Isometry3d, 4> grasps =
      GraspCandidates(box, Eigen::Quaterniond::Identity());
  // Positions are the same for all four grasps: test the workspace once.
  const Eigen::Isometry3d& g = grasps[0];
  const std::array<std::pair<const char*, Eigen::Isometry3d>, 3> points = {{
      {"grasp point G", g},
      {"approach point M", RaisedAlongBaseZ(g, waypoints.approach_distance_m)},
      {"retrieve point R", RaisedAlongBaseZ(g, waypoints.retrieve_height_m)},
  }};
  for (const auto& [name, pose] : points) {
    if (!workspace.Contains(pose.translation())) {
      return absl::StrFormat("%s %s is outside the workspace", name, Xyz(pose.translation()));
    }
  }
  if (!reachable) return "";
  for (const Eigen::Isometry3d& grasp : grasps) {
    bool all = true;
    for (double height : {0.0, waypoints.approach_distance_m, waypoints.retrieve_height_m}) {
      if (!reachable(RaisedAlongBaseZ(grasp, height))) {
        all = false;
        break;
      }
    }
    if (all) return "";
  }
  return absl::StrFormat("grasp at %s is not reachable (G, M or R, every tool rotation)",
                         Xyz(g.translation()));
}

}  // namespace

PickSelection SelectPick(const std::vector<DetectedBox>& boxes,
                         const Eigen::Isometry3d& base_T_camera, const BoxDims& dims,
                         const SelectionOptions& selection, const Workspace& workspace,
                         const WaypointOptions& waypoints, const Reachability& reachable) {
  PickSelection result;
  result.verdicts.reserve(boxes.size());
  for (size_t i = 0; i < boxes.size(); ++i) {
    BoxVerdict verdict;
    verdict.index = static_cast<int>(i);
    verdict.score = boxes[i].score;
    verdict.box = BoxToBase(boxes[i], base_T_camera, dims);
    if (!(boxes[i].score >= selection.min_score)) {
      verdict.reason = absl::StrFormat("score %.3f is below min_score %.3f", boxes[i].score,
                                       selection.min_score);
    } else if (!(verdict.box.tilt_deg <= selection.max_grasp_tilt_deg)) {
      verdict.reason = absl::StrFormat("grasp face tilted %.1f deg from base +z (max %.1f)",
                                       verdict.box.tilt_deg, selection.max_grasp_tilt_deg);
    } else {
      verdict.reason = CheckPickWaypoints(verdict.box, workspace, waypoints, reachable);
    }
    verdict.accepted = verdict.reason.empty();
    result.verdicts.push_back(std::move(verdict));
  }

  // Repeatedly the best of the rest: the highest grasp point, ties within
  // height_tie_m of it decided by score, then height, then index.
  std::vector<const BoxVerdict*> rest;
  for (const BoxVerdict& v : result.verdicts) {
    if (v.accepted) rest.push_back(&v);
  }
  while (!rest.empty()) {
    double top_z = -std::numeric_limits<double>::infinity();
    for (const BoxVerdict* v : rest) top_z = std::max(top_z, v->box.grasp_point.z());
    auto best = rest.end();
    for (auto it = rest.begin(); it != rest.end(); ++it) {
      const BoxVerdict& v = **it;
      if (v.box.grasp_point.z() < top_z - selection.height_tie_m) continue;
      if (best == rest.end() || v.score > (*best)->score ||
          (v.score == (*best)->score && v.box.grasp_point.z() > (*best)->box.grasp_point.z())) {
        best = it;
      }
    }
    result.ranked.push_back((*best)->index);
    rest.erase(best);
  }
  if (!result.ranked.empty()) result.chosen = result.ranked.front();
  return result;
}

}  // namespace cornerpose::robot_client
